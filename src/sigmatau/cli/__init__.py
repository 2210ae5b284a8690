"""The ``sigmatau`` command: parse, call the API, print.

Holds the parser and entry point (``app``), what every command shares
(``common``: options, console, exit codes, atomic writes) and one module per
command (``analyze``, ``demo``, ``stats``, ``simulate``, ``batch``), each with
``add_cli(subparsers)`` and its command function. The top layer: it may import
every other layer, and nothing but ``python -m sigmatau`` imports it.
"""

from .app import main
from .common import (  # noqa: F401  (public before the split, outside __all__)
    EXIT_DATA, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK, EXIT_TERMINATED, EXIT_USAGE,
)
from .simulate import DEMO_IMU  # noqa: F401

__all__ = ["main"]
