"""Feature 10: the status bar shows pixel, world position, region and zoom; a PNG figure of
both views with a legend can be exported."""

from __future__ import annotations

from pathlib import Path

from conftest import error_boxes, hover
from PySide6.QtCore import QPointF
from PySide6.QtGui import QImage

from ursim_gui.views import file_dialogs
from ursim_gui.views.status_bar import format_cursor, format_zoom


def test_status_bar_shows_pixel_region_and_zoom(window, qtbot):
    view = window.views["sketch"]
    hover(qtbot, view.viewport(), view.mapFromScene(QPointF(75.5, 30.5)))
    text = window.status.cursor_label.text()
    assert text.startswith("sketch  px (30, 75)") and "region 2" in text and "world" not in text
    view.set_zoom(4)
    assert window.status.zoom_label.text() == "zoom 400 %"


def test_status_bar_shows_world_coordinates_of_ros_maps(window, map_files, tmp_path, qtbot):
    yaml_path = tmp_path / "ros.yaml"
    yaml_path.write_text(
        f"image: {map_files['metric'].name}\nresolution: 0.5\norigin: [10.0, 20.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    window.documents.open_map("metric", yaml_path)
    view = window.views["metric"]
    hover(qtbot, view.viewport(), view.mapFromScene(QPointF(0.5, 119.5)))  # the lower-left pixel
    text = window.status.cursor_label.text()
    assert "px (119, 0)" in text and "world (10.25, 20.25) m" in text


def test_formatting_helpers():
    assert format_cursor("metric", 1, 2, (0.5, -1.25), 7) == "metric  px (1, 2)  world (0.50, -1.25) m  region 7"
    assert format_zoom(32) == "zoom 3200 %"


def test_export_figure_writes_a_png_with_a_legend(window, tmp_path, monkeypatch):
    window.session.link([1], [1])
    window.session.link([2], [3])
    window.actions["connectors"].setChecked(True)
    window.session.select_clique(window.session.correspondences.cliques[0].id)
    target = tmp_path / "figure.png"
    monkeypatch.setattr(file_dialogs, "ask_save_path", lambda *a, **k: Path(str(target)))
    window.actions["export_figure"].trigger()
    image = QImage(str(target))
    assert not image.isNull() and image.width() > 600 and image.height() > 600
    # The sketch's room 1 is drawn in clique 1's colour somewhere in the left half.
    colour = window.session.color_of_clique(1)
    found = any(
        abs(image.pixelColor(x, y).red() - colour[0]) < 40
        and abs(image.pixelColor(x, y).green() - colour[1]) < 40
        and abs(image.pixelColor(x, y).blue() - colour[2]) < 40
        for x in range(0, image.width() // 2, 7)
        for y in range(0, image.height() // 2, 7)
    )
    assert found
    assert window.views["sketch"].marked_regions("selection") == {1}  # hidden only while rendering
    assert all(item.isVisible() for item in window.views["sketch"].layers._marks["selection"])


def test_failed_figure_export_shows_an_error(window, tmp_path):
    assert not window.tools.export_figure(tmp_path / "nope" / "figure.png")
    assert error_boxes(window)


def test_job_progress_starts_busy_and_becomes_a_percentage(qtbot):
    from ursim_gui.views.status_bar import CursorStatusBar

    bar = CursorStatusBar()
    qtbot.addWidget(bar)
    bar.show_job(True)
    assert (bar.progress_bar.minimum(), bar.progress_bar.maximum()) == (0, 0)  # busy
    bar.show_progress(0.05, "matching")
    assert bar.progress_bar.maximum() == 0
    bar.show_progress(0.5, "matching at m = 0.225")
    assert (bar.progress_bar.maximum(), bar.progress_bar.value()) == (1000, 500)
    assert bar.currentMessage() == "matching at m = 0.225"
    bar.show_job(False)
    assert not bar.progress_bar.isVisibleTo(bar)
