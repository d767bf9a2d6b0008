"""The session bound to the map views: clique colours alike on both sides, hover highlights the partners."""

from __future__ import annotations

import numpy as np
from conftest import hover, region_point
from PySide6.QtCore import Qt


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


def test_the_sketch_laid_by_the_last_match_is_outlined_on_the_metric_map(window, qtbot):
    from ursim_core.matching import MatchConfig

    metric = window.views["metric"]
    action = window.actions["laid_sketch"]
    assert action.isChecked() and not metric.has_laid_sketch()  # nothing matched yet
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        window.jobs.match(MatchConfig())
    qtbot.waitUntil(lambda: window.matching_panel.match_button.isEnabled())
    assert window.session.last_match.laid and metric.has_laid_sketch()
    # Drawn in the sketch's clique colours: some outline pixel has a matched region's colour.
    pixels = metric.layers.laid.pixels()
    assert pixels is not None and np.count_nonzero(pixels) > 0
    action.setChecked(False)
    assert not metric.has_laid_sketch()
    action.setChecked(True)
    assert metric.has_laid_sketch()
    # The graph matcher's own pairs were not laid: nothing to show.
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        window.jobs.match(MatchConfig(elastic="off"))
    qtbot.waitUntil(lambda: window.matching_panel.match_button.isEnabled())
    assert not window.session.last_match.laid and not metric.has_laid_sketch()
