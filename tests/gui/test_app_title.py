"""The title bar names the app once: "URSIM Studio — untitled*", not "URSIM Studio — untitled* — URSIM Studio"."""

from __future__ import annotations

from PySide6.QtGui import QGuiApplication

from ursim_gui import app


def title_bar(title: str, display_name: str | None) -> str:
    """The title a window manager shows for ``title``: Qt appends the application display name, when one
    was set, to every window title that does not end with it (QPlatformWindow::formatWindowTitle, on
    X11 and Windows)."""
    if not display_name or title.endswith(display_name):
        return title
    return f"{title} — {display_name}"


def test_the_title_bar_names_the_app_once(map_files, tmp_path, monkeypatch, restore_logging):
    display_names: list[str] = []
    monkeypatch.setattr(QGuiApplication, "setApplicationDisplayName", staticmethod(display_names.append))
    titles: list[str] = []

    def keep_title(window, *_args):
        titles.append(window.windowTitle())
        window.discard_and_close()
        return 0

    monkeypatch.setattr(app, "_screenshot", keep_title)
    argv = [str(map_files["sketch"]), str(map_files["metric"]), "--screenshot", str(tmp_path / "unused.png")]
    assert app.main(argv) == 0
    (title,) = titles
    assert title.startswith("URSIM Studio")
    shown = title_bar(title, display_names[-1] if display_names else None)
    assert shown.count("URSIM Studio") == 1, shown
