"""The goal and route tools driven through the widgets on the bundled example pair (issue 15)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from PySide6.QtCore import QPoint, Qt

from ursim_core.navigation.goal import locate
from ursim_core.navigation.nav2_files import load_waypoints_yaml


@pytest.fixture
def georeferenced_window(example_window):
    """The example pair with its metric PNG georeferenced as a map_server YAML would be, so
    that goals get poses."""
    window = example_window
    session = window.session
    segmentation = session.segmentation("metric")
    session.set_map("metric", dataclasses.replace(session.map("metric"), resolution=0.05, origin=(-3.0, -2.0, 0.0)))
    session.set_segmentation("metric", segmentation)
    window.fit_views()
    return window


def _matched_sketch_points(session, count):
    """Interior points of ``count`` matched sketch regions that are adjacent in turn (a drawable route)."""
    graph = session.segmentation("sketch").graph
    matched = {r for clique in session.correspondences.cliques for r in clique.sketch_regions}
    start = min(matched)
    order = [start]
    while len(order) < count:
        nxt = [n for n in graph.neighbors(order[-1]) if n in matched and n not in order]
        if not nxt:
            break
        order.append(min(nxt))
    return [tuple(int(v) for v in graph.nodes[r]["interior"]) for r in order]


def _viewport_pos(view, row, col) -> QPoint:
    from PySide6.QtCore import QPointF

    return view.mapFromScene(QPointF(col + 0.5, row + 0.5))


def test_goal_tool_click_gives_the_core_goal_and_exports(georeferenced_window, qtbot, tmp_path):
    window = georeferenced_window
    session, view = window.session, window.views["sketch"]
    window.actions["goal_tool"].trigger()
    assert window.navigation.tools.mode == "goal" and view.stroke_mode
    row, col = _matched_sketch_points(session, 1)[0]
    position = _viewport_pos(view, row, col)
    clicked = view._pixel_at(position.toPointF())
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=position)
    goals = window.navigation.model.goals
    assert len(goals) == 1
    expected = locate(
        session.correspondences,
        session.segmentation("sketch"),
        session.segmentation("metric"),
        session.map("metric"),
        *clicked,
    )
    assert goals[0].pixel == expected.pixel and goals[0].pose == expected.pose
    assert window.navigation.tools.overlays["metric"].goal_points == [expected.pixel]
    assert "Goal in metric region" in window.statusBar().currentMessage()
    assert expected.pose is not None  # the example's metric map is a map_server YAML map

    assert window.navigation.export_json(tmp_path / "goals.json")
    document = json.loads((tmp_path / "goals.json").read_text())
    assert document["format"] == "ursim-navigation" and len(document["goals"]) == 1
    assert window.navigation.export_nav2(tmp_path / "waypoints.yaml")
    (pose,) = load_waypoints_yaml(tmp_path / "waypoints.yaml")
    assert np.allclose(pose, expected.pose)

    qtbot.keyClick(window, Qt.Key.Key_Escape)
    assert window.navigation.tools.mode == "" and not window.actions["goal_tool"].isChecked()


def test_unmatched_tap_names_the_nearest_matched_region(georeferenced_window, qtbot):
    window = georeferenced_window
    session, view = window.session, window.views["sketch"]
    window.actions["goal_tool"].trigger()
    row, col = _matched_sketch_points(session, 1)[0]
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=_viewport_pos(view, row, col))
    assert len(window.navigation.model.goals) == 1
    # Unlinking the tapped region's clique drops the goal, with a note; a new tap there names the nearest.
    region = session.segmentation("sketch").labels[row, col]
    clique = next(c for c in session.correspondences.cliques if region in c.sketch_regions)
    session.delete_clique(clique.id)
    assert window.navigation.model.goals == []
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, pos=_viewport_pos(view, row, col))
    message = window.statusBar().currentMessage()
    assert message.startswith("No goal") and "nearest matched region" in message
    assert window.navigation.model.goals == []
    # Accepting the offer places the goal in the nearest matched region, as the core says.
    offer = window.navigation.model.offer
    assert offer is not None
    window.actions["goal_nearest"].trigger()
    (goal,) = window.navigation.model.goals
    expected = locate(
        session.correspondences,
        session.segmentation("sketch"),
        session.segmentation("metric"),
        session.map("metric"),
        *offer,
    )
    assert goal.ok and goal.pixel == expected.pixel


def test_route_tool_drag_gives_waypoints_that_follow_the_cliques(georeferenced_window, qtbot, tmp_path):
    window = georeferenced_window
    session, view = window.session, window.views["sketch"]
    window.actions["route_tool"].trigger()
    assert not window.actions["goal_tool"].isChecked()
    points = _matched_sketch_points(session, 3)
    assert len(points) >= 2
    viewport = view.viewport()
    qtbot.mousePress(viewport, Qt.MouseButton.LeftButton, pos=_viewport_pos(view, *points[0]))
    for point in points[1:]:
        qtbot.mouseMove(viewport, pos=_viewport_pos(view, *point))
    qtbot.mouseRelease(viewport, Qt.MouseButton.LeftButton, pos=_viewport_pos(view, *points[-1]))
    route = window.navigation.model.route
    assert route is not None and len(route.waypoints) >= 2
    overlay = window.navigation.tools.overlays["metric"]
    assert overlay.line_points == [w.pixel for w in route.waypoints]
    assert len(window.navigation.tools.overlays["sketch"].line_points) >= len(points)

    assert window.navigation.export_json(tmp_path / "route.json")
    document = json.loads((tmp_path / "route.json").read_text())
    assert len(document["route"]["poses"]) == len(route.waypoints)
    assert window.navigation.export_nav2(tmp_path / "route.yaml")
    loaded = load_waypoints_yaml(tmp_path / "route.yaml")
    assert np.allclose(loaded, [w.pose for w in route.waypoints])

    # Deleting the first waypoint's clique (one undo step) re-plans the route without it.
    first = route.waypoints[0]
    clique = next(c for c in session.correspondences.cliques if first.metric_region in c.metric_regions)
    session.select_clique(clique.id)
    window.actions["delete_clique"].trigger()
    after = window.navigation.model.route
    assert after is not None and after != route
    window.actions["undo"].trigger()
    assert window.navigation.model.route == route


def test_new_segmentation_clears_the_goals_with_a_note(georeferenced_window, qtbot):
    window = georeferenced_window
    session = window.session
    window.actions["goal_tool"].trigger()
    row, col = _matched_sketch_points(session, 1)[0]
    window.navigation.model.tap(row, col)
    assert window.navigation.model.goals
    session.set_segmentation("sketch", session.segmentation("sketch"))
    assert window.navigation.model.goals == []
    assert "cleared" in window.statusBar().currentMessage()
