"""The matching panel: Match with its settings, input kind and scale, sketch orientation, the last result's summary."""

from __future__ import annotations

import dataclasses
import time

from PySide6.QtCore import Qt, QTimer

from ursim_core.matching import MatchConfig
from ursim_core.matching.config import ELASTIC_LAYINGS


def test_match_button_runs_in_the_worker_and_applies_the_result(window, qtbot):
    panel = window.matching_panel
    panel.m_auto.setChecked(False)
    panel.m_value.setValue(0.2)
    panel.matcher.setCurrentIndex(panel.matcher.findData("hungarian"))
    assert panel.config().m == 0.2 and panel.config().matcher == "hungarian"
    ticks = []
    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(10)
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
        assert not panel.match_button.isEnabled()  # one job at a time
    timer.stop()
    session = window.session
    assert session.last_match is not None and session.last_match.config.matcher == "hungarian"
    assert {c.source for c in session.correspondences.cliques} == {"auto"}
    assert window.table.model.rowCount() == len(session.correspondences.cliques) > 0
    assert "pairs" in panel.summary.text()
    qtbot.waitUntil(lambda: panel.match_button.isEnabled())
    assert max((b - a for a, b in zip(ticks, ticks[1:])), default=0) < 0.5


def test_a_document_reopened_from_its_file_says_its_automatic_cliques_are_there(window, tmp_path):
    """Reopened pairs said 'not matched yet' although the file held the matcher's cliques."""
    from types import SimpleNamespace

    session = window.session
    session.apply_match(SimpleNamespace(pairs=[(1, 1), (2, 2)], anchors=[(1, 1)], m=0.1, cost=0.0, reason=""))
    automatic = sum(1 for clique in session.correspondences.cliques if clique.source == "auto")
    assert automatic == 2 and window.matching_panel.summary.text().startswith("2 pairs")
    path = tmp_path / "doc.json"
    session.save(path)
    session.open(path)
    assert session.last_match is None
    assert window.matching_panel.summary.text().startswith(f"{automatic} automatic cliques from the file")


def test_the_overlay_matcher_with_a_known_scale_runs_from_the_panel(window, qtbot):
    panel = window.matching_panel
    assert panel.matcher.currentData() == "auto" and panel.scale.isEnabled()
    panel.matcher.setCurrentIndex(panel.matcher.findData("planar"))
    assert not panel.scale.isEnabled()  # the planar matcher has no use for it
    panel.matcher.setCurrentIndex(panel.matcher.findData("auto"))
    assert panel.scale.isEnabled() and panel.config().scale is None  # 0 = unknown
    panel.scale.setValue(1.0)
    # A known scale: the automatic matcher lays the maps on each other.
    assert panel.config().matcher == "auto" and panel.config().scale == 1.0
    _match_by(window, qtbot, panel.match_button)
    result = window.session.last_match
    assert result.config.matcher == "overlay" and result.pairs
    assert "pairs" in panel.summary.text()


def test_the_matching_panel_says_what_the_input_map_is(window):
    panel = window.matching_panel
    assert panel.config().input_kind is None
    panel.set_input_kind("metric")
    assert panel.config().input_kind == "metric" and panel.config().resolved().matcher == "overlay"
    panel.matcher.setCurrentIndex(panel.matcher.findData("planar"))
    assert not panel.input_kind.isEnabled() and panel.config().input_kind is None
    panel.set_input_kind(None)
    assert panel.input_kind.currentData() is None


def test_the_orientation_goes_to_the_match_config(window):
    panel = window.matching_panel
    fields = {field.name for field in dataclasses.fields(MatchConfig)}
    assert panel.config().matcher == "auto"
    panel.turn_right.click()
    panel.angle.setValue(30.0)
    panel.angle.editingFinished.emit()
    config = panel.config()
    if "orientation" in fields:  # the core's MatchConfig has the fields (added this round)
        assert config.orientation == 30.0 and config.mirrored is False
    panel.unknown.click()
    assert not panel.orientation.known and window.views["sketch"].orientation == (0.0, False)
    if "orientation" in fields:
        assert panel.config().orientation == "any"


def test_the_orientation_the_matcher_read_can_be_kept(window, qtbot):
    panel, sketch = window.matching_panel, window.views["sketch"]
    assert not panel.keep_found.isVisible()  # nothing matched yet
    _match_by(window, qtbot, panel.match_button)
    result = window.session.last_match
    found = (float(round(result.orientation[0] % 360.0, 1) % 360.0), result.orientation[1])
    assert "read the sketch" in panel.summary.text()
    assert panel.keep_found.isVisible() and panel.found_orientation.describe() in panel.keep_found.text()
    panel.keep_found.click()
    assert (panel.orientation.angle, panel.orientation.mirrored) == found == sketch.orientation
    assert not panel.keep_found.isVisible()  # it is the orientation set now
    config = panel.config()
    assert (config.orientation, config.mirrored) == found
    panel.unknown.click()
    assert panel.keep_found.isVisible()  # offered again while the last answer stands


def test_a_file_opened_again_offers_the_orientation_its_match_read(window, qtbot, tmp_path):
    panel = window.matching_panel
    _match_by(window, qtbot, panel.match_button)
    offered, readings = panel.keep_found.text(), [reading for reading, _ in panel.readings]
    window.documents.save_as(tmp_path / "pair.json")
    window.documents.open_correspondences(tmp_path / "pair.json")
    assert window.session.last_match is None  # no result in memory: the file's record speaks
    assert "automatic cliques from the file" in panel.summary.text() and "read the sketch" in panel.summary.text()
    assert panel.keep_found.isVisible() and panel.keep_found.text() == offered
    # The readings to compare, as the match ranked them, and the one its answer was laid in.
    assert len(readings) > 1 and [reading for reading, _ in panel.readings] == readings
    assert panel.answer_reading == readings[0] and window.actions["compare_readings"].isEnabled()
    panel.keep_found.click()
    assert window.views["sketch"].orientation == (panel.orientation.angle, panel.orientation.mirrored)


def test_the_summary_says_when_the_pairs_are_a_vote_over_resamplings():
    import networkx as nx

    from ursim_core.matching import match
    from ursim_gui.panels.matching_panel import describe_result

    graph = nx.path_graph(3)
    nx.set_node_attributes(graph, {0: 50, 1: 10, 2: 12}, "size")
    nx.set_node_attributes(graph, 0.3, "pca_shape")
    nx.set_node_attributes(graph, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    result = match(graph, graph.copy())
    assert "voted" not in describe_result(result)
    assert "voted over 6 resamplings" in describe_result(dataclasses.replace(result, resampling_votes=6))


def test_the_summary_names_the_reading_ranked_next():
    import networkx as nx

    from ursim_core.matching import match
    from ursim_gui.panels.matching_panel import describe_result

    graph = nx.path_graph(3)
    nx.set_node_attributes(graph, {0: 50, 1: 10, 2: 12}, "size")
    nx.set_node_attributes(graph, 0.3, "pca_shape")
    nx.set_node_attributes(graph, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    result = dataclasses.replace(
        match(graph, graph.copy()), orientation=(0.0, False), orientation_scan={(0.0, False): 0.4, (90.0, True): 0.41}
    )
    text = describe_result(result)
    assert "next best: turned 90° counter-clockwise, mirrored, ranked 2.5% worse" in text
    assert "close call" not in text
    # Reopened from a file: the record says it.
    record = {
        "config": {"orientation": "any"},
        "orientation": {"degrees": 0.0, "mirrored": False},
        "next_reading": {"degrees": 180.0, "mirrored": False, "ranked_worse_by": 0.004},
    }
    text = describe_result(None, automatic_cliques=3, record=record)
    assert "next best: turned 180° counter-clockwise, ranked 0.4% worse: a close call" in text
    # Told the orientation: nothing was read, so nothing ranked next.
    told = dataclasses.replace(result, config=dataclasses.replace(result.config, orientation=0.0))
    assert "next best" not in describe_result(told)


def test_the_summary_names_the_overlays_runner_up_for_a_robot_map():
    # Robot maps are overlaid, not matched by the planar matcher; their answer ranks every
    # orientation too, so the panel says how close the call was (Halmstad E5_05's half turn).
    import numpy as np

    from ursim_core.matching import match
    from ursim_core.segmentation import segment
    from ursim_core.synth import make_pair
    from ursim_gui.panels.matching_panel import describe_result

    plan, _ = make_pair(seed=2)
    part = segment(np.rot90(plan.free[:, : plan.free.shape[1] * 4 // 5], 1), preset="default")
    result = match(part, segment(plan.free, preset="default"), config=MatchConfig(input_kind="metric"))
    assert result.config.matcher == "overlay"
    text = describe_result(result)
    assert "next best: turned" in text and "% worse" in text, text


def test_the_panel_says_where_a_sketchs_pairs_come_from(window, qtbot):
    panel = window.matching_panel
    assert panel.config().elastic == "completed" and panel.pairs_from.isEnabled()
    panel.matcher.setCurrentIndex(panel.matcher.findData("hungarian"))
    assert not panel.pairs_from.isEnabled()  # the Hungarian baseline gives its own pairs
    panel.matcher.setCurrentIndex(panel.matcher.findData("auto"))
    panel.pairs_from.setCurrentIndex(panel.pairs_from.findData("off"))
    assert panel.config().elastic == "off"
    _match_by(window, qtbot, panel.match_button)
    assert not window.session.last_match.laid and "laid" not in panel.summary.text()
    qtbot.waitUntil(lambda: panel.match_button.isEnabled())
    panel.pairs_from.setCurrentIndex(panel.pairs_from.findData("completed"))
    _match_by(window, qtbot, panel.match_button)
    result = window.session.last_match
    assert result.laid and result.config.elastic == "completed" and result.pairs
    assert "pairs from the sketch laid and bent onto the map" in panel.summary.text()


def test_the_panel_lays_a_partial_sketch_where_its_answer_puts_it(window, qtbot):
    from ursim_core.matching.elastic import Laying
    from ursim_gui.panels.matching_panel import describe_result

    panel = window.matching_panel
    assert panel.config().elastic_laying == MatchConfig().elastic_laying == "window" and panel.laying.isEnabled()
    panel.laying.setCurrentIndex(panel.laying.findData("boxes_or_answer"))
    assert panel.config().elastic_laying == "boxes_or_answer"
    panel.matcher.setCurrentIndex(panel.matcher.findData("hungarian"))
    assert not panel.laying.isEnabled()  # the Hungarian baseline lays nothing
    panel.matcher.setCurrentIndex(panel.matcher.findData("auto"))
    _match_by(window, qtbot, panel.match_button)
    result = window.session.last_match
    assert result.laid and result.config.elastic_laying == "boxes_or_answer"
    assert result.laying.by in ("boxes", "answer")
    by_answer = dataclasses.replace(result, laying=Laying("answer", 1.0, 0.0, 1.0, 0.0))
    assert "laid where the graph answer puts it" in describe_result(by_answer)
    assert "graph answer" not in describe_result(dataclasses.replace(result, laying=None))
    by_window = dataclasses.replace(result, laying=Laying("window", 1.0, 0.0, 1.0, 0.0))
    assert "part of the map it resembles most" in describe_result(by_window)
    panel.laying.setCurrentIndex(panel.laying.findData("window"))
    assert panel.config().elastic_laying == "window"
    # Every laying the core knows is offered, and none it does not.
    offered = {panel.laying.itemData(index) for index in range(panel.laying.count())}
    assert offered == set(ELASTIC_LAYINGS)
    panel.laying.setCurrentIndex(panel.laying.findData("boxes_or_window"))
    assert panel.config().elastic_laying == "boxes_or_window"


def test_the_panel_is_told_the_sketch_shows_part_of_the_map(window):
    from ursim_core.matching.config import PARTIAL_SKETCH

    panel = window.matching_panel
    assert not panel.partial.isChecked() and panel.config().window_reading_margin == 0
    panel.partial.setChecked(True)
    config = panel.config()
    assert {name: getattr(config, name) for name in PARTIAL_SKETCH} == PARTIAL_SKETCH
    # The laying it chose stays a choice of its own; cleared, the default laying comes back.
    panel.laying.setCurrentIndex(panel.laying.findData("boxes_or_answer"))
    assert panel.config().elastic_laying == "boxes_or_answer" and panel.config().window_reading_margin > 0
    panel.laying.setCurrentIndex(panel.laying.findData(PARTIAL_SKETCH["elastic_laying"]))
    panel.partial.setChecked(False)
    assert panel.config().window_reading_margin == 0
    assert panel.config().elastic_laying == MatchConfig().elastic_laying
    # Only the planar matcher reads it.
    panel.partial.setChecked(True)
    panel.matcher.setCurrentIndex(panel.matcher.findData("hungarian"))
    assert not panel.partial.isEnabled() and panel.config().window_reading_margin == 0
    assert not panel.config().window_start


def test_the_reading_ranked_next_is_one_click_away(window, qtbot):
    panel, sketch = window.matching_panel, window.views["sketch"]
    assert not panel.try_runner_up.isVisible()  # nothing matched yet
    _match_by(window, qtbot, panel.match_button)
    first = window.session.last_match
    first_pairs = _region_pairs(window.session)
    runner_up = panel.runner_up
    assert runner_up is not None and runner_up != panel.found_orientation
    assert panel.try_runner_up.isVisible() and runner_up.describe() in panel.try_runner_up.text()
    assert runner_up.describe() in panel.summary.text()  # the summary's "next best"
    panel.set_ready(False)
    assert not panel.try_runner_up.isEnabled()  # one job at a time
    panel.set_ready(True)
    _match_by(window, qtbot, panel.try_runner_up)
    # The matcher was told the runner-up reading, and the view turned to it.
    result = window.session.last_match
    assert result is not first
    assert (result.config.orientation, result.config.mirrored) == (runner_up.angle, runner_up.mirrored)
    assert (panel.orientation.angle, panel.orientation.mirrored) == sketch.orientation
    assert panel.orientation == runner_up
    # Told the orientation, the matcher ranks no other reading: nothing more is offered.
    assert panel.runner_up is None and not panel.try_runner_up.isVisible()
    assert window.session.undo()  # the second answer is one undo step
    assert _region_pairs(window.session) == first_pairs


def _region_pairs(session) -> list:
    return sorted((c.sketch_regions, c.metric_regions) for c in session.correspondences.cliques)


def test_the_reading_ranked_next_is_an_edit_action_too(window, qtbot):
    action, panel = window.actions["match_runner_up"], window.matching_panel
    assert action.shortcut().toString() == "Ctrl+Shift+M"
    assert not action.isEnabled()  # nothing matched yet: no reading to offer
    _match_by(window, qtbot, panel.match_button)
    runner_up = panel.runner_up
    assert runner_up is not None and action.isEnabled()
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        action.trigger()
    config = window.session.last_match.config
    assert (config.orientation, config.mirrored) == (runner_up.angle, runner_up.mirrored)
    assert not action.isEnabled()  # told the orientation: no other reading ranked
    panel.match_runner_up()  # nothing offered: no match asked for
    assert window.session.last_match.config is config


def _match_by(window, qtbot, button) -> None:
    """Click ``button`` and wait until the match it starts has changed the correspondences."""
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(button, Qt.MouseButton.LeftButton)
