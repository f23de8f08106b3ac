"""The command line (`planthub`, `python -m hub`)."""
from hub.cli.main import main

__all__ = ["main"]
