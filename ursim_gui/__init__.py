"""URSIM Studio desktop app: annotate ground truth and inspect sketch-to-metric matches.

Two layers (see docs/gui_contract.md): ``ursim_gui.model`` is Qt-free and owns all state;
the modules here are thin PySide6 views over it. Start it with ``ursim-gui`` or
``python -m ursim_gui``.
"""

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """Run the app (imports Qt only when called)."""
    from ursim_gui.app import main as run

    return run(argv)


# Must run before any Qt call; see ursim_gui/qt_compat.py (does not import Qt).
from ursim_gui.qt_compat import protect_none_refcount as _protect_none_refcount

_protect_none_refcount()
