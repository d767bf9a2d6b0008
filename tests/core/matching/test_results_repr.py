"""The repr of a MatchResult shows the answer, not its matrices (it was ~7,500 characters)."""

from __future__ import annotations

import dataclasses

from ursim_core.matching.pipeline import match
from ursim_core.segmentation import segment
from ursim_core.synth.example import make_pair

HIDDEN = ("signatures", "c_matrix", "config", "m_scan", "orientation_scan")


def test_the_repr_of_a_real_match_is_short_and_shows_the_answer():
    plan, sketch = make_pair(seed=3)
    result = match(segment(sketch, preset="default"), segment(plan, preset="default"))
    assert result.pairs and result.c_matrix.size > 0 and result.signatures is not None
    text = repr(result)
    assert len(text) < 1000, len(text)
    assert text.startswith("MatchResult(pairs=") and repr(result.pairs) in text and f"m={result.m!r}" in text
    for name in HIDDEN:
        assert f"{name}=" not in text
    # Still fields: equality-free copies and dataclasses.replace keep them.
    assert {f.name for f in dataclasses.fields(result) if not f.repr} == set(HIDDEN)
    assert dataclasses.replace(result).c_matrix is result.c_matrix
