"""Issue 13, the campaign view: open a dataset folder, walk its pairs, reopen where the user stopped."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from conftest import region_point, scaled
from PySide6.QtCore import Qt

from ursim_core.correspondences import load_correspondences
from ursim_core.errors import FormatError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_gui.model.campaign import open_campaign, pair_summary
from ursim_gui.window.main_window import MainWindow


def kth_folder():
    root = dataset_root()
    folder = None if root is None else root / "ursim_kth_sketches"
    if folder is None or not folder.is_dir():
        pytest.skip(MISSING_REASON)
    return folder


def new_window(qtbot, data_dir):
    window = MainWindow(data_dir=data_dir)
    qtbot.addWidget(window)
    window.show()
    qtbot.waitExposed(window)
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


@pytest.fixture
def plain_campaign(tmp_path, labels3):
    """A plain folder: metric.png and three sketches (the three-room map and two copies)."""
    folder = tmp_path / "plain"
    folder.mkdir()
    cv2.imwrite(str(folder / "metric.png"), np.where(scaled(labels3, 2) > 0, 255, 0).astype(np.uint8))
    for name in ("s1", "s2", "s3"):
        cv2.imwrite(str(folder / f"{name}.png"), np.where(labels3 > 0, 255, 0).astype(np.uint8))
    return folder


def test_plain_folder_and_manifest_campaigns(plain_campaign, tmp_path):
    campaign = open_campaign(plain_campaign, annotator="ann", data_dir=tmp_path / "data")
    assert [p.name for p in campaign.pairs] == ["s1", "s2", "s3"]
    assert campaign.output_dir == plain_campaign / "ursim_annotations" / "ann"  # the naming rule
    assert {p.metric.name for p in campaign.pairs} == {"metric.png"}
    manifest = tmp_path / "campaign.json"
    manifest.write_text(
        json.dumps({"metric": "plain/metric.png", "sketches": ["plain/s2.png"], "annotator": "bo", "output": "out"})
    )
    from_manifest = open_campaign(manifest)
    assert [p.name for p in from_manifest.pairs] == ["s2"] and from_manifest.annotator == "bo"
    assert from_manifest.pairs[0].output == tmp_path / "out" / "s2.json"
    (plain_campaign / "metric.png").rename(plain_campaign / "other.png")
    with pytest.raises(FormatError, match="exactly one metric map"):
        open_campaign(plain_campaign, data_dir=tmp_path / "data")


def test_review_fixes_a_wrong_match_in_three_actions(plain_campaign, qtbot, tmp_path):
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=tmp_path / "out")
    session = window.session
    # Make one clique wrong (sketch a <-> metric b, b != the metric partner it should have).
    (first, *_rest) = session.correspondences.cliques
    sketch_region = first.sketch_regions[0]
    wrong = next(c.metric_regions[0] for c in session.correspondences.cliques if c.id != first.id)
    session.relink(first.id, "metric", [wrong])
    session.set_status(first.id, "pending")
    right = first.metric_regions[0]
    # 1: click the sketch region (selects its clique); 2: Ctrl+click the right metric region; 3: E.
    sketch_view, metric_view = window.views["sketch"], window.views["metric"]
    qtbot.mouseClick(sketch_view.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch_view, sketch_region))
    qtbot.mouseClick(
        metric_view.viewport(),
        Qt.MouseButton.LeftButton,
        Qt.KeyboardModifier.ControlModifier,
        region_point(metric_view, right),
    )
    qtbot.keyClick(sketch_view, Qt.Key.Key_E)
    fixed = session.clique(first.id)
    assert fixed.metric_regions == (right,) and fixed.status == "accepted" and fixed.source == "manual"


def test_accept_and_next_and_zoom_to_clique(plain_campaign, qtbot, tmp_path):
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=tmp_path / "out")
    session = window.session
    cliques = session.correspondences.cliques
    assert len(cliques) >= 2
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Space)  # nothing selected: selects the first to review
    assert session.selected_clique == cliques[0].id
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Space)  # accept it, go to the next
    assert session.clique(cliques[0].id).status == "accepted" and session.selected_clique == cliques[1].id
    window.fit_views()
    fitted = window.views["sketch"].zoom_factor()
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Z)
    assert window.views["sketch"].zoom_factor() > fitted


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
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        assert window.campaigns.open(folder, output_dir=tmp_path / "out")
    assert window.matching_panel.config().input_kind == "metric"
    assert window.session.last_match.config.resolved().matcher == "overlay"
    window.close()


def test_the_matching_panel_says_what_the_input_map_is(window):
    panel = window.matching_panel
    assert panel.config().input_kind is None
    panel.set_input_kind("metric")
    assert panel.config().input_kind == "metric" and panel.config().resolved().matcher == "overlay"
    panel.matcher.setCurrentIndex(panel.matcher.findData("planar"))
    assert not panel.input_kind.isEnabled() and panel.config().input_kind is None
    panel.set_input_kind(None)
    assert panel.input_kind.currentData() is None
