"""One module per ``pendulab`` command; each exposes ``register(subparsers)``."""
