"""The ahead-of-time build in parts: what each part holds, what a built module needs, failures."""

from __future__ import annotations

import importlib.machinery
import shutil
import subprocess

import pytest


def test_the_parts_hold_every_kernel_module_once():
    from ursim_core.segmentation.maoris.compiled import ENTRY_KERNELS, MODULE_NAME, PARTS

    held = [module for modules in PARTS.values() for module in modules]
    assert sorted(held) == sorted(ENTRY_KERNELS)
    assert next(iter(PARTS)) == MODULE_NAME


def test_built_modules_leave_no_numba_symbol_undefined():
    """pycc's C support is compiled without numba's typed containers: nothing may need them
    (an undefined symbol would fail only when first called)."""
    from ursim_core.segmentation.maoris import compile_kernels, compiled

    if shutil.which("nm") is None:
        pytest.skip("no nm to list the symbols")
    compile_kernels()
    path = compiled.ahead_module_path()
    if path is None:
        pytest.skip("no ahead-of-time build in this install")
    for name in compiled.PARTS:
        part = path.parent / (name + importlib.machinery.EXTENSION_SUFFIXES[0])
        undefined = subprocess.run(["nm", "-u", str(part)], capture_output=True, text=True, check=True).stdout
        assert [line for line in undefined.splitlines() if "numba" in line.lower() or "NRT" in line] == []


def test_a_failing_part_is_reported_with_its_output(tmp_path, monkeypatch):
    from ursim_core.segmentation.maoris import compiled

    # The child looks its part up in the real PARTS, and knows no such name: it fails.
    monkeypatch.setattr(compiled, "PARTS", {"_no_such_part": ("fusion",)})
    with pytest.raises(RuntimeError, match="(?s)_no_such_part.*KeyError"):
        compiled.build_ahead(tmp_path)
    assert not (tmp_path / compiled.DIGEST_NAME).exists()
