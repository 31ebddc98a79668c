"""Stand-in fuzz worker for tests/fmu/test_fmi_fuzz.py: announces its sequence, then dies by SIGSEGV."""

import os
import signal
import sys

if __name__ == "__main__":
    print("SEQ 5", flush=True)
    os.kill(os.getpid(), signal.SIGSEGV)
    sys.exit(0)
