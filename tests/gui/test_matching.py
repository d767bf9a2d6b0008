"""Feature 5: matching runs in a worker with progress and Cancel; the window stays responsive."""

from __future__ import annotations

import time

from PySide6.QtCore import Qt, QTimer


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


def test_cancel_drops_a_running_segmentation(window, qtbot):
    before = window.session.segmentation("metric")
    window.segmentation_panel.boxes["metric"].segment_button.click()
    assert window.status.cancel_button.isVisible()
    with qtbot.waitSignal(window.jobs.runner.cancelled, timeout=60_000):
        qtbot.mouseClick(window.status.cancel_button, Qt.MouseButton.LeftButton)
    assert window.session.segmentation("metric") is before  # result discarded
    assert not window.status.cancel_button.isVisible()
    assert window.matching_panel.match_button.isEnabled()


def test_match_without_segmentations_explains_why(window):
    from conftest import error_boxes

    window.session.set_map("sketch", window.session.map("sketch"))
    window.jobs.match(window.matching_panel.config())
    assert error_boxes(window) and "Segment both maps" in error_boxes(window)[0].text()
    assert not window.jobs.busy


def test_a_result_for_a_replaced_map_is_dropped(window, qtbot, map_files):
    before = window.session.segmentation("sketch")
    window.segmentation_panel.boxes["sketch"].segment_button.click()
    window.session.load_map("sketch", map_files["sketch"])  # replaced while the job runs
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    assert window.session.segmentation("sketch") is None  # the stale result was not applied
    assert before is not None and "dropped" in window.status.currentMessage()


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
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    result = window.session.last_match
    assert result.config.matcher == "overlay" and result.pairs
    assert "pairs" in panel.summary.text()


def test_two_georeferenced_maps_are_overlaid_at_the_scale_of_their_resolutions(window, qtbot, map_files, tmp_path):
    from ursim_core.segmentation import load_label_image

    session = window.session
    for side, resolution in (("sketch", 0.1), ("metric", 0.05)):  # the metric map is drawn twice as large
        yaml_path = tmp_path / f"{side}.yaml"
        yaml_path.write_text(
            f"image: {map_files[side].name}\nresolution: {resolution}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
        )
        session.load_map(side, yaml_path)
        session.set_segmentation(side, load_label_image(map_files[f"{side}_labels"], shape=session.map(side).shape))
    panel = window.matching_panel
    assert panel.config().scale is None  # the panel does not know; the job reads the maps
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    result = session.last_match
    assert (result.config.matcher, result.config.scale) == ("overlay", 2.0)
    assert sorted(result.pairs) == [(1, 1), (2, 2), (3, 3)]


def test_matching_again_builds_on_the_review(window, qtbot):
    """Accepted and rejected cliques used to be replaced by the next match (the review was lost)."""
    session = window.session
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    first, second = session.correspondences.cliques[:2]
    session.set_status(first.id, "accepted")
    session.set_status(second.id, "rejected")
    rejected_pair = (second.sketch_regions[0], second.metric_regions[0])

    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)

    cliques = session.correspondences.cliques
    assert [c.id for c in cliques if c.status == "accepted"] == [first.id]
    assert [c.id for c in cliques if c.status == "rejected"] == [second.id]
    assert rejected_pair not in session.last_match.pairs
    assert (first.sketch_regions[0], first.metric_regions[0]) in session.last_match.pairs
    assert "building on 2 reviewed pairs" in window.status.currentMessage()


def test_a_matcher_without_constraints_still_keeps_the_review(window, qtbot):
    from conftest import error_boxes

    session = window.session
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    accepted = session.correspondences.cliques[0]
    session.set_status(accepted.id, "accepted")
    panel = window.matching_panel
    panel.matcher.setCurrentIndex(panel.matcher.findData("vf2"))

    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)

    assert not error_boxes(window)
    assert session.last_match.config.matcher == "vf2"
    assert [c.id for c in session.correspondences.cliques if c.status == "accepted"] == [accepted.id]


def test_ctrl_m_matches_again_after_a_link(window, qtbot):
    session = window.session
    assert window.actions["match"].isEnabled()
    session.link([1], [2])
    with qtbot.waitSignal(session.correspondences_changed, timeout=60_000):
        qtbot.keyClick(window, Qt.Key.Key_M, Qt.KeyboardModifier.ControlModifier)
        assert not window.actions["match"].isEnabled()  # one job at a time
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    assert (1, 2) in session.last_match.pairs
    assert window.actions["match"].isEnabled()
