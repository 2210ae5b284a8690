"""The ``sigmatau`` command: parse, call the API, print.

Holds the parser and entry point (``app``), what every command shares
(``common``: options, console, exit codes, atomic writes) and one module per
command (``analyze``, ``demo``, ``stats``, ``simulate``, ``batch``), each with
``add_cli(subparsers)`` and its command function. The top layer: it may import
every other layer, and nothing but ``python -m sigmatau`` imports it.
"""

from .app import main

__all__ = ["main"]
