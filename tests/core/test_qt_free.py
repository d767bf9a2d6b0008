"""ursim_core must never import Qt: the core is used headless, on robots and in CI."""

import pkgutil
import subprocess
import sys

import ursim_core


def test_core_modules_import_without_qt():
    modules = [m.name for m in pkgutil.walk_packages(ursim_core.__path__, "ursim_core.")]
    assert "ursim_core.cli" in modules
    code = (
        "import importlib, sys\n"
        f"for name in {modules!r}:\n"
        "    importlib.import_module(name)\n"
        "qt = sorted(m for m in sys.modules if m.split('.')[0] in ('PySide6', 'PyQt5', 'PyQt6', 'shiboken6'))\n"
        "assert not qt, qt\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_core_sources_do_not_mention_qt_imports():
    offenders = []
    for module in pkgutil.walk_packages(ursim_core.__path__, "ursim_core."):
        spec = module.module_finder.find_spec(module.name)
        source = open(spec.origin, encoding="utf-8").read()
        if "import PySide6" in source or "from PySide6" in source:
            offenders.append(module.name)
    assert offenders == []
