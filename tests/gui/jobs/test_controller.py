"""The job controller: cancel, stale results dropped, what the status bar says, matches steered by the review."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt


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


def test_first_segmentation_says_the_kernels_compile(window, qtbot, monkeypatch):
    from ursim_core.segmentation.maoris import kernel_cache

    monkeypatch.setattr(kernel_cache, "kernels_cached", lambda: False)
    window.segmentation_panel.boxes["sketch"].segment_button.click()
    # The CLI's line, with how long it takes.
    message = window.status.currentMessage()
    assert f"Compiling the segmentation kernels (first run only, about {kernel_cache.COMPILE_SECONDS} s)" in message
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=120_000)


def test_no_compiling_note_once_the_kernels_are_cached(window, qtbot, monkeypatch):
    from ursim_core.segmentation.maoris import kernel_cache

    monkeypatch.setattr(kernel_cache, "kernels_cached", lambda: True)
    window.segmentation_panel.boxes["sketch"].segment_button.click()
    assert "Compiling" not in window.status.currentMessage()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=120_000)


def test_a_segmentation_with_no_region_says_why(window, qtbot, tmp_path, monkeypatch):
    """Two rooms with no door between them: MAORIS drops both, and the status says so, as the
    CLI does, instead of a bare "0 regions"."""
    import cv2

    from ursim_core import segmentation as segmentation_module

    asked, why = [], segmentation_module.why_no_region

    def counted(*args, **kwargs):
        asked.append(1)
        return why(*args, **kwargs)

    monkeypatch.setattr(segmentation_module, "why_no_region", counted)

    image = np.zeros((80, 170), np.uint8)
    image[5:75, 5:80] = 255
    image[5:75, 90:165] = 255
    cv2.imwrite(str(tmp_path / "closed.png"), image)
    window.session.load_map("sketch", tmp_path / "closed.png")
    window.segmentation_panel.boxes["sketch"].segment_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=120_000)
    qtbot.waitUntil(lambda: "0 regions" in window.status.currentMessage(), timeout=10_000)
    assert "2 separate areas with no opening between them" in window.status.currentMessage()
    summary = window.segmentation_panel.boxes["sketch"].summary.text()  # and it stays in the panel
    assert summary.startswith("0 regions (maoris): ") and "no opening between them" in summary
    assert len(asked) == 1, "the status bar and the panel each worked the reason out"
