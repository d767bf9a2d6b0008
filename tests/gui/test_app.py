"""The app entry point (ursim_gui.app): --screenshot writes a PNG, errors are shown, never fatal; the example opens."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path

import pytest
from PySide6.QtGui import QImage
from PySide6.QtWidgets import QMessageBox

from ursim_gui import app


def test_screenshot_option_writes_a_png_in_process(map_files, tmp_path, restore_logging):
    shot = tmp_path / "shot.png"
    code = app.main([str(map_files["sketch"]), str(map_files["metric"]), "--screenshot", str(shot)])
    assert code == 0
    image = QImage(str(shot))
    assert not image.isNull() and image.width() >= 1000
    assert (tmp_path / "userdata" / "ursim-gui.log").read_text().count("screenshot written") == 1


@pytest.mark.slow
def test_screenshot_subprocess_offscreen(map_files, tmp_path):
    shot = tmp_path / "sub.png"
    env = {**os.environ, "QT_QPA_PLATFORM": "offscreen", "URSIM_GUI_DATA_DIR": str(tmp_path / "data")}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "ursim_gui",
            str(map_files["sketch"]),
            str(map_files["metric"]),
            "--screenshot",
            str(shot),
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=180,
        cwd=Path(app.__file__).parent.parent,
    )
    assert done.returncode == 0, done.stderr
    assert shot.stat().st_size > 10_000


def test_excepthook_logs_and_shows_instead_of_crashing(qtbot, caplog, monkeypatch):
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)  # restored after the test
    app.install_excepthook()
    try:
        raise RuntimeError("boom")
    except RuntimeError:
        sys.excepthook(*sys.exc_info())
    assert any(
        "boom" in record.getMessage() or "boom" in (record.exc_text or "")
        for record in caplog.records
        if record.levelno == logging.ERROR
    )
    from PySide6.QtWidgets import QApplication

    boxes = [w for w in QApplication.topLevelWidgets() if isinstance(w, QMessageBox) and w.isVisible()]
    assert any("boom" in box.text() for box in boxes)
    for box in boxes:
        box.close()


def test_without_arguments_the_example_is_opened_segmented_matched_and_scored(qtbot, tmp_path):
    from ursim_gui.model.example import example_inputs
    from ursim_gui.window.main_window import MainWindow

    args = app.parse_args([])
    assert args.maps == [] and not args.no_example
    if example_inputs() is None:
        pytest.skip("resources/example is not generated in this checkout")
    window = MainWindow(data_dir=tmp_path / "data")
    qtbot.addWidget(window)
    assert window.open_inputs(example=True, wait=True)
    session = window.session
    assert session.map("sketch").path.parent == app.EXAMPLE_DIR
    assert session.segmentation("sketch") is not None and session.segmentation("metric") is not None
    assert session.correspondences.cliques and session.evaluation is not None
    assert window.evaluation.values["f1"].text() != "–"
