"""Campaigns in the window: open a dataset folder, walk its pairs, save each on leaving, reopen where one stopped."""

from __future__ import annotations

import os

import pytest
from conftest import new_window
from PySide6.QtCore import Qt

from ursim_core.correspondences import load_correspondences
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_gui.model.campaign import open_campaign, pair_summary


def kth_folder():
    root = dataset_root()
    folder = None if root is None else root / "ursim_kth_sketches"
    if folder is None or not folder.is_dir():
        pytest.skip(MISSING_REASON)
    return folder


def campaign_window(qtbot, tmp_path, folder, out):
    """A new window with the campaign of ``folder`` open (pairs' files in ``out``) and its first pair matched."""
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        assert window.campaigns.open(folder, output_dir=out)
    return window


def test_a_kth_campaign_of_18_pairs_through_the_widgets_and_back(qtbot, tmp_path):
    folder = kth_folder()
    out, data = tmp_path / "annotations", tmp_path / "userdata"
    window = new_window(qtbot, data)
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        assert window.campaigns.open(folder, output_dir=out)
    campaign = window.campaigns.campaign
    assert len(campaign.pairs) == 18 and window.campaign_panel.table.rowCount() == 18
    left: dict = {}  # pair name -> its file's bytes when the user left it
    for index, pair in enumerate(campaign.pairs):
        assert campaign.current == index and window.session.map("sketch").path == pair.sketch
        assert window.campaign_panel.status_text(index) == "automatic"  # matched and saved, not reviewed
        assert pair.output.is_file() and window.session.correspondences.cliques
        window.actions["accept_all"].trigger()
        assert window.campaign_panel.status_text(index) == "done"
        if index + 1 < len(campaign.pairs):
            with qtbot.waitSignal(window.campaigns.pair_ready, timeout=120_000):
                qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
        else:
            assert window.campaigns.save_current()
        left[pair.name] = pair.output.read_bytes()
        # No other pair's file was touched since the user left it.
        assert {name: (out / f"{name}.json").read_bytes() for name in left} == left
    assert window.campaign_panel.progress.value() == 18
    window.close()

    reopened = new_window(qtbot, data)
    assert reopened.campaigns.open(folder, output_dir=out)
    again = reopened.campaigns.campaign
    assert sorted(p.stem for p in out.glob("*.json") if p.name != "campaign.json") == sorted(left)
    assert again.current == 17 and reopened.session.path == again.pairs[17].output  # where the user stopped
    assert [reopened.campaign_panel.status_text(row) for row in range(18)] == ["done"] * 18
    reopened.close()
    assert {name: (out / f"{name}.json").read_bytes() for name in left} == left  # nothing rewritten


def test_leaving_a_pair_saves_it_and_reopening_restores_status_and_position(plain_campaign, qtbot, tmp_path):
    out, data = tmp_path / "out", tmp_path / "userdata"
    window = new_window(qtbot, data)
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=out)
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
    session = window.session
    session.set_status(session.correspondences.cliques[0].id, "rejected")  # in review
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_A)  # back: s2 is saved on the way
    assert pair_summary(out / "s2.json")[0] == "in review"
    assert load_correspondences(out / "s2.json").cliques[0].status == "rejected"
    assert not (out / "s3.json").exists()
    s1 = (out / "s1.json").read_bytes()
    window.close()

    reopened = new_window(qtbot, data)
    reopened.campaigns.open(plain_campaign, output_dir=out)
    panel = reopened.campaign_panel
    assert [panel.status_text(row) for row in range(3)] == ["automatic", "in review", "not started"]
    assert reopened.campaigns.campaign.current == 0 and (out / "s1.json").read_bytes() == s1
    assert reopened.preferences.annotator() == "tester"  # asked once, remembered
    assert load_correspondences(out / "s1.json").annotator == "tester"


def test_a_campaign_of_robot_maps_is_matched_as_robot_maps(qtbot, tmp_path):
    """The app matched the Halmstad robot maps as sketches (planar), where `ursim evaluate` overlays them."""
    root = dataset_root()
    folder = None if root is None else root / "ursim_halmstad_robot_maps" / "E5"
    if folder is None or not folder.is_dir():
        pytest.skip(MISSING_REASON)
    campaign = open_campaign(folder, output_dir=tmp_path / "out")
    assert {pair.input_kind for pair in campaign.pairs} == {"metric"}
    kth = dataset_root() / "ursim_kth_sketches"
    if kth.is_dir():
        assert {pair.input_kind for pair in open_campaign(kth, output_dir=tmp_path / "kth").pairs} == {"sketch"}
    window = campaign_window(qtbot, tmp_path, folder, tmp_path / "out")
    assert window.matching_panel.config().input_kind == "metric"
    assert window.session.last_match.config.resolved().matcher == "overlay"
    window.close()


def test_the_pairs_list_says_how_each_sketch_was_read_and_marks_close_calls(plain_campaign, qtbot, tmp_path):
    from ursim_gui.model.campaign import PairSummary, reading_of
    from ursim_gui.panels.campaign_panel import CLOSE_CALL_COLOUR

    out = tmp_path / "out"
    window = campaign_window(qtbot, tmp_path, plain_campaign, out)
    panel = window.campaign_panel
    record = load_correspondences(out / "s1.json").extra["matcher"]
    assert panel.reading_text(0) == reading_of(record)[0] != ""  # matched with the orientation unknown
    assert panel.reading_text(1) == panel.reading_text(2) == ""  # not matched yet
    # A close call stands out in the list, and says what to do.
    panel.show_pair(1, PairSummary("automatic", 3, 0, "turned 180° · next ranked 0.4% worse", close_call=True))
    item = panel.table.item(1, 3)
    assert item.text() == "turned 180° · next ranked 0.4% worse" and item.foreground().color() == CLOSE_CALL_COLOUR
    assert "Compare the readings" in item.toolTip()
    window.close()


def test_the_next_pair_s_sketch_is_read_ahead_while_a_pair_is_worked_on(plain_campaign, qtbot, tmp_path, monkeypatch):
    # Decoding a map on the GUI thread was the longest gap of the event loop on Next pair.
    import threading

    import ursim_core.io.maps as maps

    read_on: dict = {}
    load = maps.load_map

    def recording(path, *args, **kwargs):
        read_on.setdefault(os.path.basename(path), []).append(threading.current_thread().name)
        return load(path, *args, **kwargs)

    monkeypatch.setattr(maps, "load_map", recording)
    window = campaign_window(qtbot, tmp_path, plain_campaign, tmp_path / "out")
    assert window.session.read_ahead.pending == ((plain_campaign / "s2.png").absolute(),)
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
    assert window.session.map("sketch").path == (plain_campaign / "s2.png").absolute()
    assert [name.startswith("ursim-read-ahead") for name in read_on["s2.png"]] == [True]
    # From s2 both neighbours are read ahead; the metric map, shown already, is not read again.
    assert set(window.session.read_ahead.pending) == {
        (plain_campaign / name).absolute() for name in ("s1.png", "s3.png")
    }
    assert len(read_on["metric.png"]) == 1
    window.close()
    assert window.session.read_ahead.pending == ()


def test_another_file_opened_over_a_pair_never_overwrites_the_pair_s_file(plain_campaign, qtbot, tmp_path, monkeypatch):
    # Another annotator's file of the same sketch, or another metric map, is not the pair's
    # document: leaving it must not write it under the pair's name.
    import dataclasses

    from ursim_core.correspondences import save_correspondences
    from ursim_gui.window import dialogs

    out = tmp_path / "out"
    window = campaign_window(qtbot, tmp_path, plain_campaign, out)
    window.actions["accept_all"].trigger()
    assert window.campaigns.save_current()
    mine = (out / "s1.json").read_bytes()

    theirs = tmp_path / "theirs.json"
    save_correspondences(dataclasses.replace(load_correspondences(out / "s1.json"), annotator="vasiliki"), theirs)
    assert window.documents.open_correspondences(theirs)
    asked = []
    monkeypatch.setattr(dialogs, "ask_unsaved_changes", lambda parent, what: asked.append(what) or "discard")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
    assert (out / "s1.json").read_bytes() == mine and not asked

    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_A)  # s1 reopened from its file
    assert window.session.path == (out / "s1.json").absolute()
    assert window.documents.open_map("metric", plain_campaign / "s3.png")  # another metric map
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=60_000)
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
    assert (out / "s1.json").read_bytes() == mine
    window.close()


def test_a_pair_that_cannot_be_opened_is_shown_empty_at_its_place(plain_campaign, qtbot, tmp_path, monkeypatch):
    # The panel must never name one pair while the maps show another: edits made then would be
    # saved nowhere.
    from conftest import error_boxes

    out = tmp_path / "out"
    window = campaign_window(qtbot, tmp_path, plain_campaign, out)
    session, campaigns = window.session, window.campaigns
    session.set_status(session.correspondences.cliques[0].id, "rejected")
    (out / "s2.json").write_text("{ not json")  # the next pair's file, damaged
    assert not campaigns.next()
    assert error_boxes(window) and "s2" in error_boxes(window)[0].text()
    assert load_correspondences(out / "s1.json").cliques[0].status == "rejected"  # saved on leaving
    assert campaigns.campaign.current == 1 and window.campaign_panel.table.currentRow() == 1
    assert session.map("sketch") is None and session.correspondences.cliques == ()
    with qtbot.waitSignal(campaigns.pair_ready, timeout=180_000):
        assert campaigns.next()  # past the broken pair
    assert session.map("sketch").path == (plain_campaign / "s3.png").absolute()
    window.close()


def test_paging_faster_than_the_matcher_leaves_the_pair_landed_on_matched(plain_campaign, qtbot, tmp_path):
    # The pairs left had jobs queued; they are dropped, not run against the next pair's maps
    # (where a stale match request cleared the new pair's jobs).
    from conftest import error_boxes

    out = tmp_path / "out"
    window = campaign_window(qtbot, tmp_path, plain_campaign, out)
    campaigns = window.campaigns
    assert campaigns.next()
    assert campaigns.next()  # s2's segmentation and match still queued
    with qtbot.waitSignal(campaigns.pair_ready, timeout=180_000):
        pass
    assert campaigns.campaign.current == 2 and not error_boxes(window)
    assert window.session.correspondences.cliques and (out / "s3.json").is_file()
    assert not (out / "s2.json").exists()
    assert window.campaign_panel.status_text(1) == "not started"
    window.close()


def test_the_progress_bar_counts_a_pair_as_done_as_soon_as_it_is(plain_campaign, qtbot, tmp_path):
    window = campaign_window(qtbot, tmp_path, plain_campaign, tmp_path / "out")
    assert window.campaign_panel.progress.value() == 0
    window.actions["accept_all"].trigger()
    assert window.campaign_panel.status_text(0) == "done" and window.campaign_panel.progress.value() == 1
    window.close()


def test_a_plain_folder_with_a_model_map_is_a_campaign(tmp_path, labels3):
    # The Halmstad KT folder: four robot maps and model_simple.png.
    import cv2
    import numpy as np

    folder = tmp_path / "KT"
    folder.mkdir()
    for name in ("KPT4A_01", "KPT4A_02", "model_simple"):
        cv2.imwrite(str(folder / f"{name}.png"), np.where(labels3 > 0, 255, 0).astype(np.uint8))
    campaign = open_campaign(folder, output_dir=tmp_path / "out")
    assert [pair.name for pair in campaign.pairs] == ["KPT4A_01", "KPT4A_02"]
    assert {pair.metric.name for pair in campaign.pairs} == {"model_simple.png"}
