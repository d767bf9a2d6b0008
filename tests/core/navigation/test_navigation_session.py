"""NavigationSession: the Qt-free model behind the GUI's goal and route tools."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences
from ursim_core.errors import ParameterError
from ursim_core.io.maps import Map
from ursim_core.navigation import NAVIGATION_FORMAT, NavigationSession, load_waypoints_yaml
from ursim_core.segmentation.graph import region_graph
from ursim_core.segmentation.interface import Segmentation


def corridor(n_rooms=4, width=20):
    labels = np.zeros((15, n_rooms * width), np.int32)
    for room in range(n_rooms):
        labels[:, room * width : (room + 1) * width] = room + 1
    return Segmentation(labels=labels, graph=region_graph(labels))


@pytest.fixture
def session():
    seg = corridor()
    the_map = Map(free=seg.labels > 0, resolution=0.1, origin=(0.0, 0.0, 0.0))
    corr = Correspondences(cliques=tuple(Clique(id=r, sketch_regions=(r,), metric_regions=(r,)) for r in (1, 2, 3, 4)))
    return NavigationSession(corr, seg, seg, the_map)


def test_taps_replace_or_keep_goals_and_notify(session):
    events = []
    session.subscribe(events.append)
    session.tap(7, 5)
    session.tap(7, 45)
    assert [g.metric_region for g in session.goals] == [3]
    session.tap(7, 65, keep=True)
    assert [g.metric_region for g in session.goals] == [3, 4]
    failed = session.tap(300, 300)
    assert not failed.ok and len(session.goals) == 2  # a failed tap keeps the goals
    assert events == ["goals"] * 3
    session.unsubscribe(events.append)
    session.clear_goals()
    assert events == ["goals"] * 3 and session.goals == []


def test_drawing_a_route_and_exporting_it(session, tmp_path):
    events = []
    session.subscribe(events.append)
    with pytest.raises(ParameterError):
        session.extend_route(1, 1)
    session.begin_route(7, 2)
    session.extend_route(7, 30)
    session.extend_route(7, 30)  # a repeated point is not a change
    session.extend_route(7, 78)
    route = session.finish_route()
    assert route.metric_regions == (1, 2, 3, 4)
    assert events == ["route"] * 4
    session.save_json(tmp_path / "nav.json")
    document = json.loads((tmp_path / "nav.json").read_text())
    assert document["format"] == NAVIGATION_FORMAT and document["frame_id"] == "map"
    assert len(document["route"]["poses"]) == 4 and document["route"]["sketch_points"][0] == [7.0, 2.0]
    session.save_nav2_waypoints(tmp_path / "wps.yaml")
    assert len(load_waypoints_yaml(tmp_path / "wps.yaml")) == 4


def test_edited_cliques_move_the_goals(session):
    session.tap(7, 5)
    assert session.goals[0].metric_region == 1
    session.set_match([(1, 4)])
    assert session.goals[0].metric_region == 4
    session.set_match([(2, 2)])
    assert session.goals == []  # region 1 is no longer matched


def test_nav2_export_needs_goals_and_a_georeferenced_map(session, tmp_path):
    with pytest.raises(ParameterError, match="no goal"):
        session.save_nav2_waypoints(tmp_path / "w.yaml")
    seg = corridor()
    plain = NavigationSession([(1, 1)], seg, seg, None)
    plain.tap(7, 5)
    with pytest.raises(ParameterError, match="resolution"):
        plain.save_nav2_waypoints(tmp_path / "w.yaml")
    assert plain.to_json()["goals"][0]["pose"] is None
