"""The ``trajplan bench`` subcommand."""
from trajplan_ros.tools.bench.command import add_parser

__all__ = ['add_parser']
