"""The status bar: pixel, world position, region and zoom under the cursor; job progress."""

from __future__ import annotations

from conftest import hover
from PySide6.QtCore import QPointF

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
