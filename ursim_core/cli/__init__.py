"""The ``ursim`` command line: one module per subcommand, :func:`main` the entry point.

May import anything in :mod:`ursim_core`, lazily (inside the subcommand), so that ``ursim
--help`` loads nothing heavy.
"""

from ursim_core.cli.main import main

__all__ = ["main"]
