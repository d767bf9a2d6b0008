"""Feature 6: matched regions share their clique colour in both views, hover highlights
the partners, connector lines, and the table is synced with the views both ways."""

from __future__ import annotations

from conftest import hover, region_point
from PySide6.QtCore import QPointF, Qt


def overlay_colour(view, region: int):
    """RGB of the overlay layer at a region's interior point (premultiplied ARGB)."""
    point = view.region_scene_point(region)
    pixel = view.layers.overlay.image().pixelColor(int(point.x()), int(point.y()))
    return pixel.red(), pixel.green(), pixel.blue()


def test_matched_regions_share_the_clique_colour(window):
    session = window.session
    first = session.link([1], [3])
    second = session.link([2], [2])
    sketch, metric = window.views["sketch"], window.views["metric"]
    assert overlay_colour(sketch, 1) == overlay_colour(metric, 3) == session.color_of_clique(first)
    assert overlay_colour(sketch, 2) == overlay_colour(metric, 2) == session.color_of_clique(second)
    assert overlay_colour(sketch, 3) != overlay_colour(metric, 3)  # unmatched: neutral
    row = window.table.model.row_of(first)
    swatch = window.table.model.data(window.table.model.index(row, 0), Qt.ItemDataRole.DecorationRole)
    assert (swatch.red(), swatch.green(), swatch.blue()) == session.color_of_clique(first)


def test_hover_highlights_partners_in_the_other_view(window, qtbot):
    window.session.link([1], [2, 3])
    sketch, metric = window.views["sketch"], window.views["metric"]
    hover(qtbot, sketch.viewport(), region_point(sketch, 1))
    assert metric.marked_regions("highlight") == {2, 3}
    hover(qtbot, sketch.viewport(), region_point(sketch, 2))
    assert metric.marked_regions("highlight") == set()
    hover(qtbot, metric.viewport(), region_point(metric, 3))
    assert sketch.marked_regions("highlight") == {1}
    window.session.unlink("sketch", 1)  # an edit updates the hovered highlight
    assert sketch.marked_regions("highlight") == set()


def test_table_and_views_select_each_other(window, qtbot):
    session = window.session
    a = session.link([1], [1])
    b = session.link([3], [3])
    table = window.table
    table.view.selectRow(table.model.row_of(b))
    assert session.selected_clique == b
    assert window.views["sketch"].marked_regions("selection") == {3}
    assert window.views["metric"].marked_regions("selection") == {3}
    sketch = window.views["sketch"]
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch, 1))
    assert session.selected_clique == a
    assert table.view.selectionModel().selectedRows()[0].row() == table.model.row_of(a)
    qtbot.mouseClick(sketch.viewport(), Qt.MouseButton.LeftButton, pos=sketch.mapFromScene(QPointF(0.5, 0.5)))
    assert session.selected_clique is None and not table.view.selectionModel().selectedRows()


def test_connector_lines_follow_the_cliques(window):
    window.session.link([1], [1])
    window.session.link([2], [3])
    overlay = window.connectors
    assert not overlay.isVisible()
    window.actions["connectors"].trigger()
    assert overlay.isVisible()
    assert [(s, m) for s, m, _ in overlay.links()] == [(1, 1), (2, 3)]
    segments = overlay.visible_segments()
    assert len(segments) == 2
    sketch_end, metric_end = segments[1]
    assert sketch_end.x() < metric_end.x()  # from the left view to the right one
    window.views["metric"].set_zoom(32)  # zoomed in: some ends leave the view
    assert len(overlay.visible_segments()) < 2
    window.actions["connectors"].trigger()
    assert not overlay.isVisible()


def test_linked_zoom(window, qtbot):
    sketch, metric = window.views["sketch"], window.views["metric"]
    window.actions["link_zoom"].setChecked(True)
    sketch.set_zoom(6)
    assert metric.zoom_factor() == sketch.zoom_factor() == 6
    window.actions["link_zoom"].setChecked(False)
    sketch.set_zoom(3)
    assert metric.zoom_factor() == 6


def test_note_cell_edits_the_clique_note(window, qtbot):
    clique = window.session.link([1], [1])
    model = window.table.model
    note = model.index(model.row_of(clique), model.columnCount() - 1)
    assert model.flags(note) & Qt.ItemFlag.ItemIsEditable
    assert not model.flags(model.index(0, 1)) & Qt.ItemFlag.ItemIsEditable
    window.table.view.edit(note)
    from PySide6.QtWidgets import QLineEdit

    editor = window.table.view.findChild(QLineEdit)
    editor.setText("kitchen")
    qtbot.keyClick(editor, Qt.Key.Key_Return)  # the delegate commits on the next loop
    qtbot.waitUntil(lambda: window.session.clique(clique).note == "kitchen")
    assert model.data(note) == "kitchen"
    window.session.undo()
    assert window.session.clique(clique).note == ""
