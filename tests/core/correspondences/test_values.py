"""Correspondence values (ursim_core.correspondences.values): Clique, MapRef, Correspondences."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ursim_core.correspondences import Clique, Correspondences, MapRef

# --------------------------------------------------------------------------- values


def test_clique_normalises_sequences_and_numpy_integers():
    clique = Clique(
        id=np.int64(3),
        sketch_points=np.array([[1, 2], [3, 4]]),
        metric_points=[[5, 6]],
        sketch_regions=[np.int32(7)],
        metric_regions=(8, 9),
        score=np.float32(0.5),
    )
    assert clique.id == 3 and type(clique.id) is int
    assert clique.sketch_points == ((1, 2), (3, 4))
    assert all(type(value) is int for point in clique.sketch_points for value in point)
    assert clique.metric_points == ((5, 6),)
    assert clique.sketch_regions == (7,) and clique.metric_regions == (8, 9)
    assert clique.score == 0.5 and type(clique.score) is float


@pytest.mark.parametrize(
    "arguments",
    [
        {"id": 0},
        {"id": 1.0},
        {"id": 1, "sketch_points": [(1, 2, 3)]},
        {"id": 1, "sketch_points": [(1.5, 2)]},
        {"id": 1, "metric_points": [(-1, 2)]},
        {"id": 1, "sketch_regions": [0]},
        {"id": 1, "source": "robot"},
        {"id": 1, "status": "done"},
        {"id": 1, "score": math.nan},
        {"id": 1, "extra": {"note": "clashes with a field"}},
    ],
)
def test_invalid_clique_values_are_refused(arguments):
    with pytest.raises((ValueError, TypeError)):
        Clique(**arguments)


def test_effective_status_defaults_by_source():
    assert Clique(id=1).effective_status == "accepted"
    assert Clique(id=1, source="auto").effective_status == "pending"
    assert Clique(id=1, source="auto", status="accepted").effective_status == "accepted"


def test_mapref_normalises_and_checks():
    ref = MapRef(path="a/b.png", size=[3, 4], labels_path="c.png")
    assert ref.path == Path("a/b.png") and ref.size == (3, 4)
    with pytest.raises(ValueError):
        MapRef(sha256="xyz")
    with pytest.raises(ValueError):
        MapRef(size=(0, 4))
    with pytest.raises(ValueError):
        MapRef(extra={"path": "x"})


def test_correspondences_refuses_duplicate_ids():
    with pytest.raises(ValueError, match="duplicate clique id 2"):
        Correspondences(cliques=(Clique(id=2), Clique(id=3), Clique(id=2)))


def test_clique_helpers():
    corr = Correspondences(cliques=(Clique(id=3), Clique(id=1)))
    assert Correspondences().next_clique_id() == 1
    assert corr.next_clique_id() == 4
    replaced = corr.with_clique(Clique(id=1, note="changed"))
    assert [c.id for c in replaced.cliques] == [3, 1] and replaced.clique(1).note == "changed"
    appended = corr.with_clique(Clique(id=9))
    assert [c.id for c in appended.cliques] == [3, 1, 9]
    assert [c.id for c in corr.without_clique(3).cliques] == [1]
    assert [c.id for c in corr.with_cliques([Clique(id=5)]).cliques] == [5]
    with pytest.raises(KeyError):
        corr.without_clique(42)
    # Values can be set members and dictionary keys (the GUI keys caches on them).
    assert len({Clique(id=1, extra={"a": [1]}), Clique(id=1, extra={"a": [1]}), Clique(id=2)}) == 2
    assert {corr: "cached"}[Correspondences(cliques=(Clique(id=3), Clique(id=1)))] == "cached"
    # The original is untouched: values, not objects to mutate.
    assert [c.id for c in corr.cliques] == [3, 1]
    with pytest.raises(dataclasses.FrozenInstanceError):
        corr.annotator = "x"
