"""The ``sigmatau`` command: parse, call the API, print.

The top layer: it may import every other layer, and nothing imports it.
"""

from .app import main

__all__ = ["main"]
