"""Connector lines between matched regions, drawn over the two map views."""

from __future__ import annotations


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
