"""Fixtures of the segmentation tests."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="module")
def c_module():
    """The built C module, loaded on its own (not through the kernels' fallbacks)."""
    import importlib.util

    from ursim_core.segmentation.maoris import compile_kernels, compiled

    compile_kernels()
    path = compiled.ahead_module_path()
    if path is None:
        pytest.skip("the C kernels could not be built here (no C compiler?)")
    spec = importlib.util.spec_from_file_location(compiled.MODULE_NAME, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
