"""Automatic choice of the threshold m per map pair.

(Evidence and final rule documented after the experiments.)
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["AUTO_RULES", "choose_m", "sweep"]


def sweep(prepared, grid=None) -> list:
    """Match at every m of the grid; returns the MatchResults in grid order."""
    from . import match_prepared

    grid = prepared.config.m_grid if grid is None else grid
    return [match_prepared(prepared, float(m)) for m in grid]


def _rule_cost(results) -> list[float]:
    return [r.normalised_cost for r in results]


AUTO_RULES = {"cost": _rule_cost}


def choose_m(prepared):
    """Pick m over the grid with the configured rule and return that m's result."""
    from dataclasses import replace

    results = sweep(prepared)
    scores = AUTO_RULES[prepared.config.auto_rule](results)
    best = int(np.argmin(scores))
    chosen = results[best]
    return replace(chosen, m_scan={float(r.m): float(s) for r, s in zip(results, scores)})
