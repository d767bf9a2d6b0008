"""The model layer imports without Qt, so it runs headless and in plain scripts."""

import subprocess
import sys
from pathlib import Path

import ursim_gui.model

#: Every module of the model package, found on disk so a new one cannot be forgotten.
MODULES = ("ursim_gui.model",) + tuple(
    f"ursim_gui.model.{path.stem}"
    for path in sorted(Path(ursim_gui.model.__file__).parent.glob("*.py"))
    if path.stem != "__init__"
)


def test_importing_the_model_loads_no_pyside6():
    # A fresh interpreter: this test process may already have imported Qt for other tests.
    code = (
        "import importlib, sys\n"
        f"for name in {MODULES!r}:\n"
        "    importlib.import_module(name)\n"
        "loaded = sorted(m for m in sys.modules if m.startswith(('PySide6', 'shiboken6')))\n"
        "assert not loaded, loaded\n"
        "print('qt-free')\n"
    )
    completed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout.strip() == "qt-free"


def test_a_session_works_with_pyside6_blocked():
    # Stronger than "not imported": make importing Qt fail and use the model anyway.
    code = (
        "import sys\n"
        "sys.modules['PySide6'] = None\n"
        "from ursim_gui.model import AnnotationSession, History, Signal\n"
        "session = AnnotationSession()\n"
        "assert not session.dirty and session.window_title() == 'URSIM Studio — untitled'\n"
        "print('ok')\n"
    )
    completed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert completed.stdout.strip() == "ok"
