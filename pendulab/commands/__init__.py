"""The CLI's commands, one module each (``register(subparsers)``), and the error they raise on bad input."""

__all__ = ["CLIError"]


class CLIError(ValueError):
    """Bad command-line input (reported as one line, exit status 2)."""
