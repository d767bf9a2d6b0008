"""``ursim bench invariance``: matching accuracy on generated pairs turned, mirrored, cropped, rescaled.

Each generated pair (:func:`ursim_core.synth.make_pair`: a floor plan and a sketch of it with
exact ground-truth cliques) is matched as drawn and after one transformation of the sketch, its
ground-truth points moved alike:

- ``turned``: by an angle drawn uniformly in [0, 360) degrees (any angle, not only quarter turns);
- ``mirrored``: left-right, then turned by such an angle;
- ``cropped``: only a window of the sketch is kept, covering 50-80 % of its free space's box
  (points outside it are dropped: their cliques keep only the metric side and are not scored);
- ``rescaled``: by a factor drawn log-uniformly in [0.5, 2];
- ``all``: cropped, rescaled, mirrored and turned at once.

Both maps are segmented with the MAORIS ``default`` preset (the sketch in its canonical pose,
:func:`ursim_core.segmentation.segment_canonical`, and in its other resamplings when it is turned
onto its wall axes, for the planar matcher's vote), matched with the default
:class:`~ursim_core.matching.MatchConfig` (nothing told about the transformation) and scored by
pair F1 and place accuracy (:mod:`ursim_core.evaluation.scoring`). The transformations are drawn
from a generator seeded by the pair's seed and the kind, so every run shows the same cases.
Figures are printed, never asserted (issue 11's bar: mean F1 >= 0.95 over these kinds).

``told=True`` (``ursim bench invariance --told``) tells the matcher each case's orientation
(:func:`undoing_orientation`) and nothing else: the same cases, with the orientation's share of
the gap taken out. The read-right column cannot say as much: the cases read right are the easier
ones, so their F1 overstates what a right reading of every case would score.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
from dataclasses import dataclass

import numpy as np

__all__ = [
    "KINDS",
    "InvarianceCase",
    "undoing_orientation",
    "transformed_sketch",
    "run_case",
    "bench_invariance",
    "print_invariance",
]

KINDS = ("upright", "turned", "mirrored", "cropped", "rescaled", "all")


@dataclass(frozen=True)
class InvarianceCase:
    """One scored case: the pair's seed, the kind, what was drawn, and the scores."""

    seed: int
    kind: str
    degrees: float
    mirrored: bool
    scale: float
    kept: float
    f1: float
    place_accuracy: float
    #: Whether the matcher read the sketch in the orientation that undoes the transformation
    #: (:func:`undoing_orientation`; the same mirror image, turned within
    #: ``matching.orientation.SAME_READING`` degrees). A plan nearly symmetric under a turn can be
    #: read otherwise and still score, so F1 stays the figure; this tells where a failure lies.
    read_right: bool = True


def undoing_orientation(degrees: float, mirrored: bool) -> tuple[float, bool]:
    """The ``(degrees, mirrored)`` of :class:`~ursim_core.matching.MatchConfig` that brings a sketch
    transformed by :func:`transformed_sketch` (mirrored first, then turned ``degrees``
    counter-clockwise) back: a turn alone is undone by the opposite turn; a mirror image turned by d
    is read by mirroring it and turning it by d (mirror, turn by -d equals turn by d, mirror).

    Examples
    --------
    >>> undoing_orientation(30.0, False), undoing_orientation(30.0, True), undoing_orientation(0.0, False)
    ((330.0, False), (30.0, True), (0.0, False))
    """
    return (float(degrees) % 360.0 if mirrored else (-float(degrees)) % 360.0, bool(mirrored))


def _parameters(seed: int, kind: str) -> tuple[float, bool, float, float]:
    """(degrees, mirrored, scale, kept fraction) of a case, drawn reproducibly."""
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    degrees = float(rng.uniform(0.0, 360.0)) if kind in ("turned", "mirrored", "all") else 0.0
    mirrored = kind in ("mirrored", "all")
    scale = float(np.exp(rng.uniform(math.log(0.5), math.log(2.0)))) if kind in ("rescaled", "all") else 1.0
    kept = float(rng.uniform(0.5, 0.8)) if kind in ("cropped", "all") else 1.0
    return degrees, mirrored, scale, kept


def transformed_sketch(free: np.ndarray, points, *, degrees=0.0, mirrored=False, scale=1.0, kept=1.0, seed=0):
    """A sketch cropped, then rescaled, mirrored and turned, and its (row, col) points moved alike.

    Points that the crop removes, or that leave the canvas, become None.

    Examples
    --------
    >>> free = np.zeros((40, 60), bool); free[10:30, 5:55] = True
    >>> image, moved = transformed_sketch(free, [(20, 10)], degrees=90)
    >>> image.shape, moved
    ((60, 40), [(49, 20)])
    """
    import cv2

    free = np.asarray(free, dtype=bool)
    points = [tuple(map(float, p)) for p in points]
    if kept < 1.0:
        rows, cols = np.nonzero(free)
        low, high = np.array([rows.min(), cols.min()]), np.array([rows.max(), cols.max()]) + 1
        side = np.maximum(1, np.round((high - low) * math.sqrt(kept))).astype(int)
        rng = np.random.default_rng([seed, 7])
        start = low + np.array([rng.integers(0, max(1, high[k] - low[k] - side[k] + 1)) for k in range(2)])
        free = free[start[0] : start[0] + side[0], start[1] : start[1] + side[1]]
        points = [
            (r - start[0], c - start[1]) if 0 <= r - start[0] < side[0] and 0 <= c - start[1] < side[1] else None
            for r, c in points
        ]
    rows, cols = free.shape
    theta = math.radians(degrees)
    # (x, y) = (col, row); mirror first, then scale, then turn counter-clockwise on the screen.
    mirror = np.array([[-1.0, 0.0], [0.0, 1.0]]) if mirrored else np.eye(2)
    turn = np.array([[math.cos(theta), math.sin(theta)], [-math.sin(theta), math.cos(theta)]])
    linear = turn @ (scale * mirror)
    corners = np.array([[0, 0], [cols - 1, 0], [0, rows - 1], [cols - 1, rows - 1]], float) @ linear.T
    offset = -corners.min(axis=0)
    # Rounded first: cos(90 degrees) is 6e-17, not 0, and must not add a column.
    width, height = (np.ceil(np.round(corners.max(axis=0) + offset, 6)) + 1).astype(int)
    matrix = np.hstack([linear, offset[:, None]])
    image = cv2.warpAffine(free.astype(np.uint8) * 255, matrix, (int(width), int(height)), flags=cv2.INTER_LINEAR)
    moved = []
    for point in points:
        if point is None:
            moved.append(None)
            continue
        x, y = linear @ np.array([point[1], point[0]]) + offset
        r, c = round(y), round(x)
        moved.append((r, c) if 0 <= r < height and 0 <= c < width else None)
    return image >= 128, moved


def _kept(segmentations: dict | None, key, make):
    """``make()``, kept in ``segmentations`` under ``key`` and taken from there again (made every
    time when ``segmentations`` is None)."""
    if segmentations is None:
        return make()
    if key not in segmentations:
        segmentations[key] = make()
    return segmentations[key]


def run_case(
    seed: int,
    kind: str,
    *,
    config=None,
    plan_segmentation=None,
    plan_copy: bool = False,
    told: bool = False,
    segmentations: dict | None = None,
) -> InvarianceCase:
    """Generate pair ``seed``, transform its sketch as ``kind`` says, match and score it.

    ``plan_copy``: transform a copy of the floor plan instead of the sketch (a robot-map-like
    input: exact walls, only part of the building when cropped). ``told``: the matcher is told the
    orientation that undoes the transformation (``MatchConfig.orientation`` and ``mirrored``).
    ``segmentations``: a dict that keeps the transformed sketch's segmentation for a later call
    on the same case (it does not depend on what the matcher is told)."""
    from ursim_core.correspondences import regions_at_points
    from ursim_core.evaluation.place import place_problem, score_places
    from ursim_core.evaluation.scoring import score_matches
    from ursim_core.matching import MatchConfig, match
    from ursim_core.matching.orientation import same_reading
    from ursim_core.segmentation import segment_canonical
    from ursim_core.synth import ground_truth_correspondences, make_pair

    plan, sketch = make_pair(seed=seed)
    truth = ground_truth_correspondences(plan, sketch)
    if plan_copy:
        truth = dataclasses.replace(
            truth, cliques=tuple(dataclasses.replace(c, sketch_points=c.metric_points) for c in truth.cliques)
        )
    degrees, mirrored, scale, kept = _parameters(seed, kind)
    flat = [p for clique in truth.cliques for p in clique.sketch_points]
    image, moved = transformed_sketch(
        plan.free if plan_copy else sketch.free,
        flat,
        degrees=degrees,
        mirrored=mirrored,
        scale=scale,
        kept=kept,
        seed=seed,
    )
    config = config or MatchConfig()
    if told:
        right_degrees, right_mirrored = undoing_orientation(degrees, mirrored)
        config = config.replace(orientation=right_degrees, mirrored=right_mirrored)
    # As ursim match: a sketch turned onto its wall axes is also segmented in its other
    # resamplings when the planar matcher will vote over them.
    resampled = config.resampling_vote and config.resolved().matcher == "planar"
    sketch_seg = _kept(
        segmentations,
        (seed, kind, plan_copy, resampled),
        lambda: segment_canonical(image, preset="default", resampled=resampled),
    )
    metric_seg = plan_segmentation if plan_segmentation is not None else segment_canonical(plan.free, preset="default")
    result = match(sketch_seg, metric_seg, config=config)
    points = iter(moved)
    regions, point_cliques = [], []
    for clique in truth.cliques:
        sketch_points = [p for p in (next(points) for _ in clique.sketch_points) if p is not None]
        point_cliques.append((sketch_points, list(clique.metric_points)))
        regions.append(
            (
                {r for r in regions_at_points(sketch_seg.labels, sketch_points) if r},
                {r for r in regions_at_points(metric_seg.labels, clique.metric_points) if r},
            )
        )
    f1 = score_matches(result.pairs, regions).f1
    problem = place_problem(point_cliques, sketch_seg.labels, metric_seg.labels)
    place = score_places(result.pairs, problem, metric_seg.graph).accuracy
    read_right = same_reading(result.orientation, undoing_orientation(degrees, mirrored))
    return InvarianceCase(seed, kind, degrees, mirrored, scale, kept, f1, place, read_right)


def bench_invariance(
    seeds=range(8),
    kinds=KINDS,
    *,
    config=None,
    progress=None,
    plan_copy: bool = False,
    told: bool = False,
    segmentations: dict | None = None,
) -> list[InvarianceCase]:
    """Every kind for every seed (the plan of a seed segmented once); ``plan_copy``, ``told`` and
    ``segmentations`` (the plans' segmentations kept there too): see :func:`run_case`."""
    from ursim_core.segmentation import segment_canonical
    from ursim_core.synth import make_pair

    cases = []
    for seed in seeds:
        plan_segmentation = _kept(
            segmentations, ("plan", seed), lambda: segment_canonical(make_pair(seed=seed)[0].free, preset="default")
        )
        for kind in kinds:
            case = run_case(
                seed,
                kind,
                config=config,
                plan_segmentation=plan_segmentation,
                plan_copy=plan_copy,
                told=told,
                segmentations=segmentations,
            )
            cases.append(case)
            if progress is not None:
                progress(case)
    return cases


def print_invariance(cases: list[InvarianceCase]) -> None:
    """Per kind: mean F1 and place accuracy, how many were read in the right orientation and their
    mean F1 against the others', the worst case; then the mean over the kinds."""
    print(
        f"{'kind':10s} {'pairs':>5s} {'mean F1':>8s} {'place acc.':>10s} {'read right':>10s} "
        f"{'F1 right / wrong':>16s} {'worst F1':>9s}  worst case"
    )
    means = []
    for kind in dict.fromkeys(case.kind for case in cases):
        group = [case for case in cases if case.kind == kind]
        worst = min(group, key=lambda case: case.f1)
        f1 = statistics.fmean(case.f1 for case in group)
        places = [case.place_accuracy for case in group if not math.isnan(case.place_accuracy)]
        place = statistics.fmean(places) if places else math.nan
        means.append((f1, place))
        right = [case.f1 for case in group if case.read_right]
        wrong = [case.f1 for case in group if not case.read_right]
        split = " / ".join(f"{statistics.fmean(part):.3f}" if part else "-" for part in (right, wrong))
        detail = f"seed {worst.seed}: {worst.degrees:.0f} deg{' mirrored' if worst.mirrored else ''}, scale {worst.scale:.2f}, kept {worst.kept:.2f}"
        print(
            f"{kind:10s} {len(group):5d} {f1:8.3f} {place:10.3f} {f'{len(right)}/{len(group)}':>10s} "
            f"{split:>16s} {worst.f1:9.3f}  {detail}"
        )
    print(
        f"{'mean':10s} {len(cases):5d} {statistics.fmean(m[0] for m in means):8.3f} "
        f"{statistics.fmean(m[1] for m in means):10.3f}   (issue 11 bar: mean F1 >= 0.95)"
    )
