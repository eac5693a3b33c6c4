"""The command line: ``pfaff demo ring|pendulum``."""

from pfaff.cli.main import main

__all__ = ["main"]
