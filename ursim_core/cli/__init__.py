"""The ``ursim`` command line: one module per subcommand, :func:`main` the entry point.

What several subcommands share has its own module: ``common`` (usage errors, map options, staged
output folders, the overwrite check), ``inputs`` (the files an input names: a YAML map's image, a
correspondence file's maps and label images) and ``match_options`` (a pair's options, for
``match`` and ``match-batch``).

May import anything in :mod:`ursim_core`, lazily (inside the subcommand), so that ``ursim
--help`` loads nothing heavy.
"""

from ursim_core.cli.main import main

__all__ = ["main"]
