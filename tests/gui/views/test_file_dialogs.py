"""The open and save dialogs never freeze on special files such as /proc."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

_PROC_SCRIPT = textwrap.dedent(
    """
    import sys, time
    from PySide6.QtCore import Qt, QTimer
    from PySide6.QtTest import QTest
    from PySide6.QtWidgets import QApplication, QFileDialog, QLineEdit
    from ursim_gui.window.main_window import MainWindow

    app = QApplication([])
    window = MainWindow(data_dir=sys.argv[1])
    window.show()

    def drive():
        dialog = next(w for w in app.topLevelWidgets() if isinstance(w, QFileDialog) and w.isVisible())
        edit = dialog.findChild(QLineEdit, "fileNameEdit")
        QTest.keyClicks(edit, "/proc/")
        QTest.keyClick(edit, Qt.Key.Key_Return)
        for _ in range(50):
            app.processEvents()
            time.sleep(0.02)
        dialog.setDirectory("/proc")
        for _ in range(50):
            app.processEvents()
            time.sleep(0.02)
        dialog.grab()
        print("responsive", flush=True)
        dialog.reject()

    QTimer.singleShot(200, drive)
    window.documents.save_as()
    window.discard_and_close()
    """
)


@pytest.mark.skipif(not Path("/proc/kmsg").exists(), reason="needs /proc/kmsg (Linux)")
def test_the_save_dialog_stays_responsive_in_proc(tmp_path):
    # In a child process: on the old code the GUI thread blocked forever reading /proc/kmsg.
    env = {"QT_QPA_PLATFORM": "offscreen", "URSIM_GUI_DATA_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    try:
        done = subprocess.run(
            [sys.executable, "-c", _PROC_SCRIPT, str(tmp_path)], capture_output=True, text=True, timeout=60, env=env
        )
    except subprocess.TimeoutExpired:
        pytest.fail("the save dialog froze on /proc/")
    assert "responsive" in done.stdout, done.stderr[-2000:]
