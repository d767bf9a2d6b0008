"""Fixtures shared by the matching tests."""

from __future__ import annotations

import pytest

from ursim_core.matching import kernels


@pytest.fixture
def c_kernel():
    """The matcher's C module; the test is skipped where it cannot be built (no C compiler)."""
    module = kernels.kernel()
    if module is None:
        pytest.skip("the matcher's C kernels could not be built here (no C compiler)")
    return module
