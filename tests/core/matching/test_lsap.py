"""The direct load of SciPy's assignment solver gives scipy.optimize's answers and errors."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
from scipy import optimize

SHAPES = [(1, 1), (3, 3), (4, 7), (9, 2), (30, 30)]

# Runs in a fresh process, where scipy.optimize is not imported, so the direct load is used.
_CHILD = """
import json, sys, numpy as np
from ursim_core.matching.lsap import linear_sum_assignment
out = {"optimize_imported": None, "results": [], "errors": []}
for rows, cols, maximize in json.loads(sys.argv[1]):
    rng = np.random.default_rng(rows * 31 + cols)
    cost = rng.random((rows, cols)); cost[rng.random((rows, cols)) < 0.2] = 0.5
    r, c = linear_sum_assignment(cost, maximize)
    out["results"].append([r.tolist(), c.tolist()])
try:
    linear_sum_assignment(np.array([[np.inf, np.inf], [1.0, np.inf]]))
except ValueError as error:
    out["errors"].append(str(error))
out["optimize_imported"] = "scipy.optimize" in sys.modules
print(json.dumps(out))
"""


def test_direct_load_gives_scipy_optimize_answers_and_errors_without_importing_it():
    cases = [[rows, cols, maximize] for rows, cols in SHAPES for maximize in (False, True)]
    result = subprocess.run(
        [sys.executable, "-c", _CHILD, json.dumps(cases)], capture_output=True, text=True, check=True, env=os.environ
    )
    child = json.loads(result.stdout.strip().splitlines()[-1])
    assert child["optimize_imported"] is False
    for (rows, cols, maximize), (got_rows, got_cols) in zip(cases, child["results"], strict=True):
        rng = np.random.default_rng(rows * 31 + cols)
        cost = rng.random((rows, cols))
        cost[rng.random((rows, cols)) < 0.2] = 0.5
        expected_rows, expected_cols = optimize.linear_sum_assignment(cost, maximize)
        assert (got_rows, got_cols) == (expected_rows.tolist(), expected_cols.tolist())
    try:
        optimize.linear_sum_assignment(np.array([[np.inf, np.inf], [1.0, np.inf]]))
    except ValueError as error:
        assert child["errors"] == [str(error)]


def test_in_a_process_that_imported_scipy_optimize_it_is_the_public_function(monkeypatch):
    from ursim_core.matching import lsap

    monkeypatch.setattr(lsap, "_function", None)
    rows, cols = lsap.linear_sum_assignment(np.array([[4.0, 1.0], [2.0, 0.5]]))
    assert lsap._function is optimize.linear_sum_assignment
    assert cols.tolist() == [1, 0]
