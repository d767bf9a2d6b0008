"""The anchors list: the last match's anchors listed and marked on the maps, cleared by a new segmentation."""

from __future__ import annotations

from conftest import answer_file_dialogs


def test_anchors_are_marked_and_listed_after_a_match(window, qtbot):
    from types import SimpleNamespace

    result = SimpleNamespace(pairs=[(1, 1), (2, 2), (3, 3)], anchors=[(1, 1), (3, 3)], m=0.1, cost=1.0, reason="")
    window.session.apply_match(result)
    anchors = window.anchors.list
    assert anchors.count() == 2 and "sketch 1" in anchors.item(0).text()
    assert window.views["sketch"].marked_regions("anchors") == {1, 3}
    assert window.views["metric"].marked_regions("anchors") == {1, 3}
    anchors.itemClicked.emit(anchors.item(1))
    assert window.session.selection == {"sketch": frozenset({3}), "metric": frozenset({3})}


def test_resegmenting_clears_the_anchors_and_the_match_summary(window, qtbot, map_files, monkeypatch):
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        window.matching_panel.match_button.click()
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    assert window.anchors.list.count() > 0 and "pairs" in window.matching_panel.summary.text()
    assert window.views["sketch"].marked_regions("anchors")

    answer_file_dialogs(monkeypatch, map_files["sketch_labels"])
    window.segmentation_panel.boxes["sketch"].load_labels_requested.emit("sketch")
    assert window.session.anchors == [] and window.anchors.list.count() == 0
    assert "pairs" not in window.matching_panel.summary.text()
    assert window.views["sketch"].marked_regions("anchors") == set()


def test_each_anchor_says_whether_the_answer_pairs_it_too(window):
    # Anchors are paired before matching; the answer may pair them otherwise, and a dashed
    # outline on a region the answer leaves out must not read as a contradiction.
    from types import SimpleNamespace

    result = SimpleNamespace(pairs=[(1, 1), (2, 2)], anchors=[(1, 1), (3, 2)], m=0.1, cost=1.0, reason="")
    window.session.apply_match(result)
    anchors = window.anchors.list
    assert anchors.item(0).text().endswith("(in the answer)")
    assert anchors.item(1).text().endswith("(not in the answer)")
    assert "other partners" in anchors.item(1).toolTip()
