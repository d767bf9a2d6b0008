"""Dock tab bars: one per tabified group, against its docks, none left over between the map views."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QMainWindow, QTabBar

from ursim_gui.window.dock_tabs import stray_tab_bars


def _tab_groups(window: QMainWindow) -> dict[tuple[str, ...], list[QTabBar]]:
    """Visible, on-screen dock tab bars of the window by the titles of their tabs."""
    groups: dict[tuple[str, ...], list[QTabBar]] = {}
    inside = window.rect()
    for bar in window.findChildren(QTabBar, options=Qt.FindChildOption.FindDirectChildrenOnly):
        if bar.isVisible() and inside.intersects(bar.geometry()):
            titles = tuple(bar.tabText(i) for i in range(bar.count()))
            groups.setdefault(titles, []).append(bar)
    return groups


def _assert_clean_tabs(window) -> None:
    centre = window.centralWidget().geometry()
    groups = _tab_groups(window)
    assert set(groups) == {("Segmentation", "Campaign"), ("Evaluation", "Agreement", "Anchors")}
    for titles, bars in groups.items():
        assert len(bars) == 1, f"{titles}: {len(bars)} tab bars on screen"
        assert not bars[0].geometry().intersects(centre), f"{titles}: a tab bar over the map views"
    assert stray_tab_bars(window) == []


def test_the_dock_tab_bars_sit_against_their_docks_on_a_first_start(window):
    _assert_clean_tabs(window)


def test_a_restored_layout_leaves_no_tab_bar_over_the_map_views(qtbot, tmp_path):
    from ursim_gui.window.main_window import MainWindow

    data = tmp_path / "data"
    first = MainWindow(data_dir=data)
    qtbot.addWidget(first)
    first.resize(1400, 900)
    first.show()
    qtbot.waitExposed(first)
    first.discard_and_close()  # saves the dock layout, as a user's session does
    first.jobs.runner.shutdown()

    second = MainWindow(data_dir=data)
    qtbot.addWidget(second)
    second.show()
    qtbot.waitExposed(second)
    try:
        _assert_clean_tabs(second)
    finally:
        second.jobs.runner.shutdown()


def test_docks_tabified_after_the_start_get_their_tab_bar(window, qtbot):
    window.tabifyDockWidget(window.docks["table"], window.docks["matching"])
    window.hide()
    window.show()  # the start's clean-up does not run again
    qtbot.waitExposed(window)

    def laid_out() -> list:
        return _tab_groups(window).get(("Correspondences", "Matching"), [])

    qtbot.waitUntil(lambda: len(laid_out()) == 1, timeout=3000)  # Qt lays the docks out later
    bars = laid_out()
    bar = bars[0].geometry()
    # Against the group's current dock (the other one waits off screen), sharing an edge.
    shown = [window.docks[name].geometry() for name in ("table", "matching")]
    assert any(bar.adjusted(-1, -1, 1, 1).intersects(dock) and not bar.intersects(dock) for dock in shown)
