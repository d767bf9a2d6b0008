"""The segmentation panel: Segment with a method, preset and parameters, Load label image, display options."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import error_boxes
from PySide6.QtCore import Qt

from ursim_gui.views import file_dialogs


def test_segment_button_runs_maoris_with_the_chosen_preset(window, qtbot):
    box = window.segmentation_panel.boxes["sketch"]
    box.preset.setCurrentText("default")
    box.spins["doors"].setValue(55)
    assert box.overrides() == {"doors": 55}
    with qtbot.waitSignal(window.session.segmentation_changed, timeout=60_000):
        qtbot.mouseClick(box.segment_button, Qt.MouseButton.LeftButton)
        assert window.status.progress_bar.isVisible()  # job UI shows while it runs
    segmentation = window.session.segmentation("sketch")
    assert segmentation.method == "maoris" and segmentation.params["doors"] == 55
    assert segmentation.n_regions >= 2
    assert box.summary.text().startswith(f"{segmentation.n_regions} regions")
    qtbot.waitUntil(lambda: not window.jobs.busy)
    assert not window.status.progress_bar.isVisible()


def test_load_label_image_button(window, map_files, monkeypatch):
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(map_files["metric_labels"])))
    window.session.set_map("metric", window.session.map("metric"))  # drops the segmentation
    assert window.session.segmentation("metric") is None
    window.segmentation_panel.boxes["metric"].load_button.click()
    assert window.session.segmentation("metric").method == "label-image"
    assert window.views["metric"].labels() is not None


def test_label_image_of_the_wrong_size_is_refused(window, map_files, monkeypatch):
    monkeypatch.setattr(file_dialogs, "ask_open_path", lambda *a, **k: Path(str(map_files["sketch_labels"])))
    before = window.session.segmentation("metric")
    window.segmentation_panel.boxes["metric"].load_button.click()
    assert error_boxes(window)
    assert window.session.segmentation("metric") is before


def test_display_options_reach_both_views(window, qtbot):
    panel, views = window.segmentation_panel, window.views
    panel.opacity.setValue(80)
    assert all(view.overlay_opacity() == pytest.approx(0.8) for view in views.values())
    panel.toggles["outlines"].setChecked(False)
    assert not views["sketch"].layers.outlines.isVisible() and not window.actions["outlines"].isChecked()
    window.actions["region_ids"].trigger()  # menu and checkbox stay in sync
    assert panel.toggles["region_ids"].isChecked()
    assert views["metric"].visible_ids() == {1, 2, 3}
    panel.toggles["graph"].setChecked(True)
    assert views["sketch"].layers.graph_item.isVisible()
    assert views["sketch"].layers.graph_item.path().elementCount() > 0


def test_the_panel_offers_every_segmenter_of_the_registry():
    from ursim_core.segmentation import SEGMENTERS, method_presets
    from ursim_gui.panels.segmentation_panel import SideSegmentationBox

    box = SideSegmentationBox("metric")
    assert [box.method.itemText(i) for i in range(box.method.count())] == list(SEGMENTERS)
    assert {"maoris", "watershed", "learned"} <= set(SEGMENTERS)
    for method in SEGMENTERS:
        box.method.setCurrentText(method)
        assert [box.preset.itemText(i) for i in range(box.preset.count())] == list(method_presets(method))
        assert box.spins and box.overrides() == {}
    box.method.setCurrentText("watershed")
    assert set(box.spins) == {"door_ratio", "min_size"}
    box.method.setCurrentText("maoris")
    assert set(box.spins) == {"threshold", "margin", "ripples", "doors"}


def test_watershed_chosen_in_the_panel_segments_saves_and_reopens_as_watershed(window, qtbot, tmp_path):
    box = window.segmentation_panel.boxes["metric"]
    box.method.setCurrentText("watershed")
    box.preset.setCurrentText("robot")
    box.spins["door_ratio"].setValue(0.8)
    assert box.overrides() == {"door_ratio": 0.8}
    with qtbot.waitSignal(window.session.segmentation_changed, timeout=60_000):
        qtbot.mouseClick(box.segment_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not window.jobs.busy)
    segmentation = window.session.segmentation("metric")
    assert segmentation.method == "watershed" and segmentation.params["door_ratio"] == 0.8
    assert box.summary.text() == f"{segmentation.n_regions} regions (watershed)"
    path = tmp_path / "pair.json"
    window.session.save(path)
    window.session.open(path)
    reopened = window.session.segmentation("metric")
    assert reopened.method == "watershed" and reopened.params["door_ratio"] == 0.8
    assert (reopened.labels == segmentation.labels).all()


def test_learned_merging_from_the_panel(window, qtbot):
    box = window.segmentation_panel.boxes["sketch"]
    box.method.setCurrentText("learned")
    assert box.preset.currentText() == "default"
    with qtbot.waitSignal(window.session.segmentation_changed, timeout=120_000):
        qtbot.mouseClick(box.segment_button, Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: not window.jobs.busy, timeout=120_000)
    segmentation = window.session.segmentation("sketch")
    assert segmentation.method == "learned" and segmentation.n_regions >= 2
