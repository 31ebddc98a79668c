"""An independent restatement of RealAIGym's robustness-v2 benchmark, for tests (see ``reference.py``)."""
