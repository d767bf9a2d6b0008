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
