"""The agreement panel through the widgets: a second annotator's folder, the per-pair table, CSV export."""

from __future__ import annotations

import shutil

import cv2
import numpy as np
import pytest
from conftest import scaled
from PySide6.QtCore import Qt

from ursim_core.correspondences import load_correspondences, save_correspondences
from ursim_gui.views import file_dialogs
from ursim_gui.window.main_window import MainWindow


@pytest.fixture
def plain_campaign(tmp_path, labels3):
    folder = tmp_path / "plain"
    folder.mkdir()
    cv2.imwrite(str(folder / "metric.png"), np.where(scaled(labels3, 2) > 0, 255, 0).astype(np.uint8))
    for name in ("s1", "s2"):
        cv2.imwrite(str(folder / f"{name}.png"), np.where(labels3 > 0, 255, 0).astype(np.uint8))
    return folder


def test_agreement_view_through_the_widgets(plain_campaign, qtbot, tmp_path, monkeypatch):
    window = MainWindow(data_dir=tmp_path / "userdata")
    qtbot.addWidget(window)
    window.show()
    out = tmp_path / "a"
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=out)
    window.actions["accept_all"].trigger()
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_D)
    window.actions["accept_all"].trigger()
    window.campaigns.save_current()

    # Annotator B: the same files, but B rejects one clique of s1.
    second = tmp_path / "b"
    shutil.copytree(out, second)
    corr = load_correspondences(second / "s1.json")
    first = corr.cliques[0]
    save_correspondences(
        corr.with_clique(first.__class__(**{**first.__dict__, "status": "rejected"})), second / "s1.json"
    )

    monkeypatch.setattr(file_dialogs, "ask_folder", lambda *a, **k: second)
    panel = window.agreement_panel
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        qtbot.keyClick(window.views["sketch"], Qt.Key.Key_A)  # back to s1
    panel.second.setCurrentText("Folder of JSON files…")
    panel.second_chosen.emit("Folder of JSON files…")
    assert window.session.reference is not None  # B's s1 is the reference: A vs B on the maps
    assert "FP" in window.views["sketch"].badge_texts().values()  # the clique B rejected
    assert window.evaluation.values["f1"].text() not in ("–", "1.000")

    with qtbot.waitSignal(window.jobs.result_ready, timeout=180_000):
        panel.compute_button.click()
    assert panel.table.rowCount() == 3 and panel.cell(2, 0) == "ALL"
    ceiling_header = panel.table.horizontalHeaderItem(7)
    assert ceiling_header.text() == "F1 ceiling vs A" and "best mean F1" in ceiling_header.toolTip()
    assert panel.cell(1, 1) == "1.000" and panel.cell(0, 1) not in ("1.000", "–")  # s2 agrees, s1 does not
    target = tmp_path / "agreement.csv"
    monkeypatch.setattr(file_dialogs, "ask_save_path", lambda *a, **k: target)
    panel.export_button.click()
    assert target.read_text().splitlines()[-1].startswith("ALL,")
    window.discard_and_close()
