"""Issue 13, agreement between annotators: per pair and whole set, disagreements marked, CSV export."""

from __future__ import annotations

import shutil

import cv2
import numpy as np
import pytest
from conftest import scaled
from PySide6.QtCore import Qt

from ursim_core.correspondences import Clique, Correspondences, load_correspondences, save_correspondences
from ursim_gui.model.agreement import agreement_csv, pair_agreement, pooled
from ursim_gui.views import file_dialogs
from ursim_gui.window.main_window import MainWindow


def at(region: int, scale: int = 1) -> tuple[int, int]:
    """A point inside room ``region`` (1 | 2 | 3) of the three-room map."""
    return (30 * scale, (25, 75, 120)[region - 1] * scale)


def clique(i, sketch, metric, **kw):
    return Clique(id=i, sketch_points=[at(sketch)], metric_points=[at(metric, 2)], **kw)


def test_pair_agreement_counts_f1_and_disagreeing_cliques(labels3):
    a = Correspondences(
        cliques=(clique(1, 1, 1, source="auto"), clique(2, 2, 3, source="auto"), clique(3, 3, 2, status="rejected"))
    )
    b = Correspondences(cliques=(clique(1, 1, 1), clique(2, 2, 2)))
    result = pair_agreement("p", a, b, labels3, scaled(labels3, 2))
    a_vs_b = result.comparisons["A vs B"]
    assert (a_vs_b.tp, a_vs_b.fp, a_vs_b.fn, a_vs_b.f1) == (1, 1, 1, 0.5)
    # Place accuracy: B's room 1 is reached through A's (1, 1); B's room 2 is sent to room 3 by A.
    assert a_vs_b.place == 0.5
    assert result.disagreeing == (2,)  # the rejected clique 3 is no claim
    assert result.comparisons["matcher vs A"].f1 == 1.0  # A kept both automatic cliques
    # The best one-to-one answer for both: (1, 1) and one of A's and B's readings of room 2,
    # B's found first; no answer scores above 0.75 on average.
    assert (result.comparisons["ceiling vs A"].f1, result.comparisons["ceiling vs B"].f1) == (0.5, 1.0)
    whole = pooled([result, result])
    assert (whole["A vs B"].tp, whole["A vs B"].fp, whole["A vs B"].f1) == (2, 2, 0.5)
    lines = agreement_csv([result]).splitlines()
    assert (
        lines[0].startswith("pair,A_vs_B_tp") and lines[1].startswith("p,1,1,1,0.5000") and lines[2].startswith("ALL,")
    )


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
