"""The exact ground truth of a generated pair: the cliques of the places a plan and its sketch share."""

from __future__ import annotations

from pathlib import Path

from ursim_core.synth.drawing import Sketch
from ursim_core.synth.floor_plans import FloorPlan, interior_points

__all__ = ["ground_truth_pairs", "ground_truth_correspondences"]


def _shared_points(plan: FloorPlan, sketch: Sketch) -> list[tuple[int, tuple[int, int], tuple[int, int]]]:
    in_sketch, in_plan = interior_points(sketch.rooms), interior_points(plan.rooms)
    return [(place, in_sketch[place], in_plan[place]) for place in sorted(in_plan) if place in in_sketch]


def ground_truth_pairs(plan: FloorPlan, sketch: Sketch) -> list[tuple[list[tuple[int, int]], list[tuple[int, int]]]]:
    """One (sketch points, metric points) clique per place drawn in both maps, by place id.

    Each side has one point, the place's most interior pixel (see :func:`interior_points`).

    Examples
    --------
    >>> from ursim_core.synth import generate_floor_plan, sketchify
    >>> plan = generate_floor_plan(seed=3)
    >>> sketch = sketchify(plan, seed=3)
    >>> pairs = ground_truth_pairs(plan, sketch)
    >>> len(pairs) == len(plan.places) - len(sketch.dropped)
    True
    >>> all(sketch.rooms[s[0]] == plan.rooms[m[0]] for s, m in pairs)
    True
    """
    return [([s], [m]) for _, s, m in _shared_points(plan, sketch)]


def ground_truth_correspondences(
    plan: FloorPlan, sketch: Sketch, *, sketch_path: str | Path | None = None, metric_path: str | Path | None = None
):
    """The ground truth as a :class:`~ursim_core.correspondences.Correspondences` value.

    One clique per place in both maps, numbered from 1 in place order, noted
    ``"place <id> <kind>"``; region lists are left empty (they depend on a segmentation,
    see :func:`ursim_core.correspondences.assign_regions`).

    Examples
    --------
    >>> from ursim_core.synth import make_pair
    >>> plan, sketch = make_pair(seed=5)
    >>> corr = ground_truth_correspondences(plan, sketch)
    >>> corr.cliques[0].note
    'place 1 corridor'
    >>> corr.metric.size == plan.free.shape
    True
    """
    from ursim_core.correspondences import Clique, Correspondences, MapRef

    kinds = plan.kinds
    cliques = tuple(
        Clique(id=index, sketch_points=(s,), metric_points=(m,), source="manual", note=f"place {place} {kinds[place]}")
        for index, (place, s, m) in enumerate(_shared_points(plan, sketch), start=1)
    )
    return Correspondences(
        sketch=MapRef(path=sketch_path, size=tuple(sketch.free.shape)),
        metric=MapRef(path=metric_path, size=tuple(plan.free.shape)),
        cliques=cliques,
        annotator="ursim_core.synth (generated ground truth)",
    )
