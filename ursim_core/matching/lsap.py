"""The linear sum assignment of SciPy, without importing all of ``scipy.optimize``.

``from scipy.optimize import linear_sum_assignment`` runs ``scipy/optimize/__init__.py``,
which imports scipy.linalg, scipy.sparse.linalg, scipy.special and scipy.fft: 0.4-0.6 s of a
whole ``ursim match`` of a KTH pair (about a third of it), for one C function. SciPy
implements that function in the extension module ``scipy/optimize/_lsap``, which needs
only NumPy; :func:`linear_sum_assignment` loads it directly, and falls back to the public
import when that module is not where SciPy 1.11-1.17 put it (a test checks both agree).
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
from pathlib import Path

import numpy as np

__all__ = ["linear_sum_assignment"]

_function = None


def _load():
    if "scipy.optimize" in sys.modules:  # already paid for: use the public function
        return sys.modules["scipy.optimize"].linear_sum_assignment
    try:
        import scipy

        folder = Path(scipy.__file__).parent / "optimize"
        for suffix in importlib.machinery.EXTENSION_SUFFIXES:
            path = folder / f"_lsap{suffix}"
            if path.is_file():
                spec = importlib.util.spec_from_file_location("scipy.optimize._lsap", path)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                return module.linear_sum_assignment
    except Exception:
        pass
    from scipy.optimize import linear_sum_assignment as public

    return public


def linear_sum_assignment(cost, maximize: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``scipy.optimize.linear_sum_assignment(cost, maximize)``: rows and their columns.

    Examples
    --------
    >>> rows, cols = linear_sum_assignment(np.array([[4.0, 1.0], [2.0, 0.5]]))
    >>> rows.tolist(), cols.tolist()
    ([0, 1], [1, 0])
    """
    global _function
    if _function is None:
        _function = _load()
    return _function(cost, maximize)
