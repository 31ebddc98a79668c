"""``python -m pendulab``: the same entry point as the ``pendulab`` console script."""

from ._entry import run

run()
