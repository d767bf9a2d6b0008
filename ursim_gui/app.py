"""Entry point of the desktop app: ``ursim-gui [SKETCH METRIC] [--correspondences FILE] [--screenshot PATH]``.

Sets up logging (a log file in the user data folder and stderr), an excepthook that logs
and shows unexpected errors instead of crashing, then opens the main window with the
given inputs, or the bundled example pair when there are none.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import traceback
from pathlib import Path

from ursim_gui.model.example import EXAMPLE_DIR

__all__ = ["main", "parse_args", "user_data_dir", "configure_logging", "install_excepthook", "EXAMPLE_DIR"]

APP_NAME = "ursim-studio"
_log = logging.getLogger("ursim_gui")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        prog="ursim-gui", description="Annotate and inspect sketch-to-metric map matches (URSIM)."
    )
    parser.add_argument("maps", nargs="*", metavar="MAP", help="SKETCH METRIC: the two maps (image or ROS YAML)")
    parser.add_argument(
        "--correspondences", "-c", metavar="FILE", help="open a correspondence JSON (and the maps it names)"
    )
    parser.add_argument(
        "--screenshot", metavar="PATH", help="load, segment and match, save a PNG of the window to PATH and exit"
    )
    parser.add_argument("--no-example", action="store_true", help="start empty instead of opening the bundled example")
    args = parser.parse_args(argv)
    if len(args.maps) not in (0, 2):
        parser.error("give both maps (SKETCH METRIC) or none")
    return args


def user_data_dir() -> Path:
    """Folder for the log and autosave files (``$URSIM_GUI_DATA_DIR`` overrides it)."""
    override = os.environ.get("URSIM_GUI_DATA_DIR")
    if override:
        folder = Path(override)
    else:
        from PySide6.QtCore import QStandardPaths

        location = QStandardPaths.writableLocation(QStandardPaths.StandardLocation.GenericDataLocation)
        folder = Path(location or Path.home() / ".local" / "share") / APP_NAME
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def configure_logging(folder: Path) -> Path:
    """Log INFO and above to ``<folder>/ursim-gui.log`` and WARNING and above to stderr."""
    log_path = folder / "ursim-gui.log"
    root = logging.getLogger()
    root.setLevel(logging.INFO)
    for handler in list(root.handlers):
        if getattr(handler, "_ursim_gui", False):
            root.removeHandler(handler)
    formatter = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    file_handler = logging.FileHandler(log_path, encoding="utf-8")
    file_handler.setFormatter(formatter)
    stderr_handler = logging.StreamHandler(sys.stderr)
    stderr_handler.setLevel(logging.WARNING)
    stderr_handler.setFormatter(formatter)
    for handler in (file_handler, stderr_handler):
        handler._ursim_gui = True  # so a second main() in one process does not duplicate them
        root.addHandler(handler)
    return log_path


def install_excepthook(parent_getter=lambda: None) -> None:
    """Log uncaught exceptions and show them in a dialog; the app keeps running."""

    def hook(kind, value, tb):
        if issubclass(kind, KeyboardInterrupt):
            sys.__excepthook__(kind, value, tb)
            return
        details = "".join(traceback.format_exception(kind, value, tb))
        _log.error("unexpected error\n%s", details)
        from PySide6.QtWidgets import QApplication

        if QApplication.instance() is not None:
            from ursim_gui.views.messages import show_error

            show_error(
                parent_getter(), "Unexpected error", f"{kind.__name__}: {value}\n\nThe details are in the log file."
            )

    sys.excepthook = hook


def main(argv: list[str] | None = None) -> int:
    """Run the app; returns the process exit code."""
    args = parse_args(sys.argv[1:] if argv is None else argv)
    folder = user_data_dir()
    log_path = configure_logging(folder)
    from PySide6.QtWidgets import QApplication

    from ursim_gui.window.main_window import MainWindow

    app = QApplication.instance() or QApplication([sys.argv[0] if sys.argv else "ursim-gui"])
    # No application display name: Qt appends it to every window title on X11 and Windows, and the
    # window's title already starts with "URSIM Studio" (the session's window_title), so the
    # title bar said it twice ("URSIM Studio — untitled* — URSIM Studio").
    app.setApplicationName(APP_NAME)
    window = MainWindow(data_dir=folder)
    install_excepthook(lambda: window)
    _log.info("URSIM Studio started; log file %s", log_path)
    sketch, metric = (Path(p) for p in args.maps) if args.maps else (None, None)
    correspondences = Path(args.correspondences) if args.correspondences else None
    use_example = sketch is None and correspondences is None and not args.no_example
    if args.screenshot:
        return _screenshot(window, Path(args.screenshot), sketch, metric, correspondences, use_example)
    window.show()
    window.jobs.runner.prewarm()
    if not window.documents.offer_recovery():
        window.open_inputs(sketch, metric, correspondences, example=use_example)
    return app.exec()


def _screenshot(window, path: Path, sketch, metric, correspondences, use_example: bool) -> int:
    from PySide6.QtWidgets import QApplication

    window.resize(1680, 1000)
    window.show()
    ok = window.open_inputs(sketch, metric, correspondences, example=use_example, wait=True)
    for _ in range(5):
        QApplication.processEvents()
    window.fit_views()
    QApplication.processEvents()
    if not window.grab().save(str(path), "PNG"):
        _log.error("could not write the screenshot %s", path)
        return 1
    _log.info("screenshot written to %s", path)
    window.discard_and_close()
    return 0 if ok else 2


if __name__ == "__main__":
    raise SystemExit(main())
