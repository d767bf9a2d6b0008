"""A map view: zoom around the cursor, pan, fit, sharp pixels, hover and clicks in map pixels, a turned sketch."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import hover, region_point
from PySide6.QtCore import QPoint, QPointF, QRectF, Qt
from PySide6.QtGui import QPainter, QWheelEvent
from PySide6.QtWidgets import QApplication

from ursim_gui.model.region_style import region_colour_table
from ursim_gui.views.map_view import MAX_ZOOM, MapView


def wheel(view: MapView, position: QPoint, steps: int) -> None:
    """Send a real wheel event to the viewport (qtbot has no wheel helper)."""
    global_pos = view.viewport().mapToGlobal(position)
    event = QWheelEvent(
        QPointF(position),
        QPointF(global_pos),
        QPoint(),
        QPoint(0, 120 * steps),
        Qt.MouseButton.NoButton,
        Qt.KeyboardModifier.NoModifier,
        Qt.ScrollPhase.NoScrollPhase,
        False,
    )
    QApplication.sendEvent(view.viewport(), event)


@pytest.fixture
def view(qtbot, grey3, segmentation3):
    view = MapView("sketch")
    qtbot.addWidget(view)
    view.resize(600, 300)
    view.show()
    qtbot.waitExposed(view)
    view.set_image(grey3)
    view.set_segmentation(segmentation3.labels, segmentation3.graph)
    view.set_region_colours(region_colour_table(3))
    return view


def test_wheel_zooms_around_the_cursor_up_to_3200_percent(view):
    cursor = view.mapFromScene(QPointF(75.5, 30.5))
    before = view.mapToScene(cursor)
    zoom = view.zoom_factor()
    wheel(view, cursor, 2)
    assert view.zoom_factor() == pytest.approx(zoom * 1.25**2)
    after = view.mapToScene(cursor)
    assert abs(after.x() - before.x()) < 1.0 and abs(after.y() - before.y()) < 1.0  # point under the cursor stays
    for _ in range(40):
        wheel(view, cursor, 3)
    assert view.zoom_factor() == pytest.approx(MAX_ZOOM)
    assert not view.renderHints() & QPainter.RenderHint.SmoothPixmapTransform


def test_fit_to_window_shows_the_whole_map_and_follows_resizes(view, qtbot):
    view.set_zoom(10)
    view.fit_to_window()
    visible = view.mapToScene(view.viewport().rect()).boundingRect()
    assert visible.contains(view.sceneRect().adjusted(1, 1, -1, -1))
    fitted = view.zoom_factor()
    view.resize(300, 150)
    qtbot.waitUntil(lambda: view.zoom_factor() < fitted)  # still fitted after a resize
    view.set_zoom(4)
    view.resize(600, 300)
    qtbot.wait(20)
    assert view.zoom_factor() == 4  # a chosen zoom is kept


def test_drag_pans_without_selecting(qtbot, view):
    view.set_zoom(8)
    view.centerOn(75, 30)
    clicks = []
    view.region_clicked.connect(lambda region, add: clicks.append(region))
    start = view.horizontalScrollBar().value()
    centre = view.viewport().rect().center()
    qtbot.mousePress(view.viewport(), Qt.MouseButton.LeftButton, pos=centre)
    for dx in (10, 30, 60):
        qtbot.mouseMove(view.viewport(), centre + QPoint(dx, 0))
    qtbot.mouseRelease(view.viewport(), Qt.MouseButton.LeftButton, pos=centre + QPoint(60, 0))
    assert start > 60 and view.horizontalScrollBar().value() == start - 60
    assert clicks == []


def test_click_hover_and_cursor_report_map_pixels(qtbot, view):
    clicks, hovers, cursors = [], [], []
    view.region_clicked.connect(lambda region, add: clicks.append((region, add)))
    view.region_hovered.connect(hovers.append)
    view.cursor_moved.connect(lambda row, col: cursors.append((row, col)))
    room3 = view.mapFromScene(QPointF(120.5, 30.5))
    hover(qtbot, view.viewport(), room3)
    assert hovers[-1] == 3 and cursors[-1] == (30, 120)
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, Qt.KeyboardModifier.ControlModifier, room3)
    assert clicks == [(3, True)]


def test_pixels_are_nearest_neighbour_at_high_zoom(qtbot, view):
    """At 3200 % a map pixel is a 32x32 block of one colour (no smoothing)."""
    grey = np.zeros((8, 8), np.uint8)
    grey[::2, ::2] = 255
    view.set_image(grey)
    view.set_zoom(MAX_ZOOM)
    view.centerOn(4, 4)
    image = view.viewport().grab().toImage()
    centre = view.mapFromScene(QPointF(4.5, 4.5))  # middle of white pixel (4, 4)
    values = {
        image.pixelColor(centre.x() + dx, centre.y() + dy).red() for dx in range(-14, 15, 7) for dy in range(-14, 15, 7)
    }
    assert values == {255}
    neighbour = view.mapFromScene(QPointF(5.5, 4.5))
    assert image.pixelColor(neighbour).red() < 250


def test_layers_and_marks(view):
    view.set_selection([2])
    view.set_highlight([1, 3])
    view.set_anchors([1])
    assert view.marked_regions("selection") == {2}
    assert view.marked_regions("highlight") == {1, 3}
    assert view.marked_regions("anchors") == {1}
    view.set_overlay_opacity(0.8)
    assert view.overlay_opacity() == pytest.approx(0.8)
    view.set_segmentation(None)
    assert view.marked_regions("selection") == set()


def test_drop_reports_paths(view, tmp_path):
    from PySide6.QtCore import QMimeData, QUrl
    from PySide6.QtGui import QDropEvent

    dropped = []
    view.files_dropped.connect(dropped.extend)
    data = QMimeData()
    data.setUrls([QUrl.fromLocalFile(str(tmp_path / "map.png"))])
    event = QDropEvent(
        QPointF(10, 10), Qt.DropAction.CopyAction, data, Qt.MouseButton.NoButton, Qt.KeyboardModifier.NoModifier
    )
    view.dropEvent(event)
    assert dropped == [tmp_path / "map.png"]


def test_turning_the_sketch_keeps_points_in_the_image_frame(window, qtbot):
    session, panel, sketch = window.session, window.matching_panel, window.views["sketch"]
    interior = tuple(int(v) for v in session.segmentation("sketch").graph.nodes[1]["interior"])
    panel.turn_left.click()
    panel.mirror.click()
    assert sketch.orientation == (90.0, True)
    assert panel.orientation.angle == 90.0 and panel.orientation.mirrored
    # The view is turned: the map's width now runs vertically on screen.
    top_left, top_right = sketch.mapFromScene(0, 0), sketch.mapFromScene(100, 0)
    assert abs(top_left.x() - top_right.x()) < abs(top_left.y() - top_right.y())
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch, 1))
    assert session.selection["sketch"] == frozenset({1})
    qtbot.mouseClick(
        window.views["metric"].viewport(), Qt.MouseButton.LeftButton, pos=region_point(window.views["metric"], 1)
    )
    qtbot.keyClick(sketch, Qt.Key.Key_L)
    assert session.correspondences.cliques[0].sketch_points == (interior,)  # original pixel frame


def test_a_map_drawn_small_on_a_large_sheet_is_fitted_to_its_drawn_part(qtbot):
    view = MapView("sketch")
    qtbot.addWidget(view)
    view.resize(600, 300)
    view.show()
    qtbot.waitExposed(view)
    grey = np.zeros((1000, 2000), np.uint8)
    grey[400:500, 900:1100] = 255  # a drawing of 100 x 200 px in the middle of the sheet
    view.set_image(grey, drawn=(400, 500, 900, 1100))
    visible = view.mapToScene(view.viewport().rect()).boundingRect()
    assert visible.contains(QRectF(900, 400, 200, 100))
    assert visible.width() < 300 and visible.height() < 300  # the drawing and its margin, not the sheet
    view.set_zoom(view.zoom_factor() / 16)  # a wheel may still zoom out to the whole sheet
    assert view.mapToScene(view.viewport().rect()).boundingRect().contains(view.sceneRect())
    view.fit_to_window()
    assert view.mapToScene(view.viewport().rect()).boundingRect().width() < 300
    view.set_image(grey)  # no drawn part given: the whole map
    assert view.mapToScene(view.viewport().rect()).boundingRect().contains(view.sceneRect().adjusted(1, 1, -1, -1))


@pytest.mark.parametrize("cols", [820, 830, 840, 850, 900])
def test_a_fit_that_brings_scroll_bars_settles(qtbot, cols):
    # The drawn part smaller than the sheet: fitted, the sheet overflows and the bars come; a fit
    # to the viewport as it then is went back and forth between two zooms without end (round 57).
    view = MapView("sketch")
    qtbot.addWidget(view)
    view.resize(600, 300)
    view.show()
    qtbot.waitExposed(view)
    zooms = []
    view.zoom_changed.connect(zooms.append)
    view.set_image(np.full((400, cols), 255, np.uint8), drawn=(4, 396, 60, cols - 60))
    qtbot.wait(200)
    assert len(zooms) < 6
    visible = view.mapToScene(view.viewport().rect()).boundingRect()
    assert visible.contains(QRectF(60, 4, cols - 120, 392))  # the drawn part whole, bars or not
