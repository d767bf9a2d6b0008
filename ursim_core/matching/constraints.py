"""What a person has already said about a pair of maps, as constraints on the matcher's answer.

An annotator who reviews an automatic answer links some regions by hand, accepts some cliques and
rejects others. Matching again (another m, another orientation, after a fix of the segmentation)
must build on that instead of starting over: the planar matcher's seed-and-expand step takes the
pairs a person vouched for as locked pairs of every hypothesis, so one right pair can bring its
neighbours along (and with them the orientation), and a rejected pair is never proposed again.

:class:`MatchConstraints` holds, in region ids:

- ``fixed``: one-to-one pairs every answer contains;
- ``forbidden``: pairs no answer contains;
- ``excluded_sketch`` / ``excluded_metric``: regions no answer pairs (the other regions of a clique
  that joins several regions on a side, and the regions of a half-made clique: they belong to what a
  person said, which a one-to-one pair cannot express).

:func:`constraints_from_cliques` derives them from correspondence cliques; ``prepare`` and ``match``
(:mod:`ursim_core.matching.pipeline`) take them as ``constraints=``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

from ursim_core.errors import ParameterError

__all__ = [
    "CONSTRAINED_MATCHERS",
    "MatchConstraints",
    "IndexConstraints",
    "constraints_from_cliques",
    "index_constraints",
    "allowed_pairs",
    "pairs_beside_review",
]

#: The matchers that honour constraints (``MatchConfig.resolved().matcher``); VF2 does not:
#: ``prepare`` refuses constraints for it.
CONSTRAINED_MATCHERS = ("planar", "hungarian", "overlay")


@dataclass(frozen=True)
class MatchConstraints:
    """Pairs an answer must contain or avoid, and regions it must leave alone (region ids).

    Parameters
    ----------
    fixed : iterable of (sketch region, metric region)
        One-to-one: a region appears in at most one fixed pair.
    forbidden : iterable of (sketch region, metric region)
    excluded_sketch, excluded_metric : iterable of int

    Raises
    ------
    ParameterError
        A region in two fixed pairs, a fixed pair also forbidden, or a fixed region excluded.

    Examples
    --------
    >>> constraints = MatchConstraints(fixed=[(1, 4)], forbidden=[(2, 5)])
    >>> constraints.fixed, bool(constraints), bool(MatchConstraints())
    (((1, 4),), True, False)
    >>> MatchConstraints(fixed=[(1, 4), (1, 5)])
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: field 'constraints': sketch region 1 is in two fixed pairs
    """

    fixed: tuple = ()
    forbidden: frozenset = field(default_factory=frozenset)
    excluded_sketch: frozenset = field(default_factory=frozenset)
    excluded_metric: frozenset = field(default_factory=frozenset)

    def __post_init__(self):
        fixed = tuple((int(a), int(b)) for a, b in self.fixed)
        object.__setattr__(self, "fixed", fixed)
        object.__setattr__(self, "forbidden", frozenset((int(a), int(b)) for a, b in self.forbidden))
        object.__setattr__(self, "excluded_sketch", frozenset(int(r) for r in self.excluded_sketch))
        object.__setattr__(self, "excluded_metric", frozenset(int(r) for r in self.excluded_metric))
        for side, index, excluded in (("sketch", 0, self.excluded_sketch), ("metric", 1, self.excluded_metric)):
            seen: set = set()
            for pair in fixed:
                region = pair[index]
                if region in seen:
                    raise ParameterError(f"{side} region {region} is in two fixed pairs", field="constraints")
                if region in excluded:
                    raise ParameterError(f"{side} region {region} is both fixed and excluded", field="constraints")
                seen.add(region)
        for pair in fixed:
            if pair in self.forbidden:
                raise ParameterError(f"pair {pair} is both fixed and forbidden", field="constraints")

    def __bool__(self) -> bool:
        return bool(self.fixed or self.forbidden or self.excluded_sketch or self.excluded_metric)

    def check_regions(self, sketch_regions: Iterable[int], metric_regions: Iterable[int]) -> None:
        """Raise :class:`ParameterError` naming a region the maps' segmentations do not have."""
        known = {"sketch": set(sketch_regions), "metric": set(metric_regions)}
        named = {
            "sketch": [a for a, _ in self.fixed] + [a for a, _ in self.forbidden] + sorted(self.excluded_sketch),
            "metric": [b for _, b in self.fixed] + [b for _, b in self.forbidden] + sorted(self.excluded_metric),
        }
        for side, regions in named.items():
            unknown = sorted({r for r in regions if r not in known[side]})
            if unknown:
                listed = ", ".join(map(str, unknown))
                raise ParameterError(
                    f"{side} region(s) {listed} not in the {side} segmentation (constraints made for another one?)",
                    field="constraints",
                )


@dataclass(frozen=True)
class IndexConstraints:
    """:class:`MatchConstraints` in the planar matcher's vertex indices."""

    fixed: tuple = ()
    forbidden: frozenset = frozenset()
    excluded_first: frozenset = frozenset()
    excluded_second: frozenset = frozenset()


def index_constraints(constraints: MatchConstraints | None, sketch_nodes, metric_nodes) -> IndexConstraints | None:
    """``constraints`` in the index form of the nodes' order (None when there are none).

    Examples
    --------
    >>> index_constraints(MatchConstraints(fixed=[(7, 3)]), [5, 7], [3, 9]).fixed
    ((1, 0),)
    """
    if not constraints:
        return None
    sketch_index = {node: i for i, node in enumerate(sketch_nodes)}
    metric_index = {node: i for i, node in enumerate(metric_nodes)}
    constraints.check_regions(sketch_index, metric_index)
    return IndexConstraints(
        fixed=tuple((sketch_index[a], metric_index[b]) for a, b in constraints.fixed),
        forbidden=frozenset((sketch_index[a], metric_index[b]) for a, b in constraints.forbidden),
        excluded_first=frozenset(sketch_index[r] for r in constraints.excluded_sketch),
        excluded_second=frozenset(metric_index[r] for r in constraints.excluded_metric),
    )


def constraints_from_cliques(cliques, *, sizes: Mapping[str, Mapping[int, float]] | None = None) -> MatchConstraints:
    """The constraints a person's review of ``cliques`` puts on the next answer.

    - A clique a person made or vouched for (``source='manual'``, or status ``accepted``) with
      regions on both sides: its largest sketch region and largest metric region (by ``sizes``;
      the first listed without them) become a fixed pair, its other regions are excluded. With
      regions on one side only (half-made): those regions are excluded.
    - A ``rejected`` clique: each of its pairs of regions is forbidden.
    - Pending automatic cliques say nothing: the next answer replaces them.

    Parameters
    ----------
    cliques : iterable of :class:`ursim_core.correspondences.Clique`
    sizes : {'sketch': {region: size}, 'metric': {...}}, optional

    Examples
    --------
    >>> from ursim_core.correspondences import Clique
    >>> reviewed = [
    ...     Clique(id=1, sketch_regions=(2,), metric_regions=(5, 6), source="manual"),
    ...     Clique(id=2, sketch_regions=(3,), metric_regions=(7,), source="auto", status="rejected"),
    ...     Clique(id=3, sketch_regions=(4,), metric_regions=(8,), source="auto"),
    ... ]
    >>> c = constraints_from_cliques(reviewed, sizes={"sketch": {}, "metric": {5: 10, 6: 40}})
    >>> c.fixed, sorted(c.forbidden), sorted(c.excluded_metric)
    (((2, 6),), [(3, 7)], [5])
    """
    sizes = sizes or {}

    def largest(regions, side):
        side_sizes = sizes.get(side, {})
        return max(regions, key=lambda region: (side_sizes.get(region, 0), -regions.index(region)))

    fixed, forbidden, excluded_sketch, excluded_metric = [], set(), set(), set()
    vouched: list = []
    for clique in cliques:
        sketch, metric = list(clique.sketch_regions), list(clique.metric_regions)
        if clique.status == "rejected":
            forbidden.update((a, b) for a in sketch for b in metric)
        elif clique.is_reviewed:
            vouched.append((sketch, metric))
    taken_sketch, taken_metric = set(), set()
    for sketch, metric in vouched:
        if sketch and metric:
            pair = (largest(sketch, "sketch"), largest(metric, "metric"))
            if pair[0] not in taken_sketch and pair[1] not in taken_metric and pair not in forbidden:
                fixed.append(pair)
                taken_sketch.add(pair[0])
                taken_metric.add(pair[1])
        excluded_sketch.update(sketch)
        excluded_metric.update(metric)
    # A region in two vouched cliques keeps the first fixed pair; every other region is excluded.
    return MatchConstraints(
        fixed=fixed,
        forbidden=forbidden,
        excluded_sketch=excluded_sketch - taken_sketch,
        excluded_metric=excluded_metric - taken_metric,
    )


def allowed_pairs(pairs, constraints: MatchConstraints | None) -> list[tuple[int, int]]:
    """The pairs that ``constraints`` leave, in order, once each: none that is forbidden or holds a
    region of a fixed pair or an excluded region (the fixed pairs themselves are not added).

    Examples
    --------
    >>> allowed_pairs([(1, 1), (2, 2), (3, 3), (4, 4), (4, 4)], MatchConstraints(fixed=[(1, 2)], forbidden=[(3, 3)]))
    [(4, 4)]
    """
    pairs = list(dict.fromkeys((int(a), int(b)) for a, b in pairs))
    if not constraints:
        return pairs
    taken_sketch = constraints.excluded_sketch | {a for a, _ in constraints.fixed}
    taken_metric = constraints.excluded_metric | {b for _, b in constraints.fixed}
    return [
        (a, b)
        for a, b in pairs
        if a not in taken_sketch and b not in taken_metric and (a, b) not in constraints.forbidden
    ]


def pairs_beside_review(pairs, cliques) -> list:
    """The pairs of an answer that a review of ``cliques`` leaves to add, in order, once each.

    A pair is left out when a rejected clique holds it, or when a clique a person made or
    accepted already holds one of its regions (that region gets no second, automatic partner):
    :func:`allowed_pairs` under :func:`constraints_from_cliques`, whose fixed and excluded regions
    are all the regions of those cliques. Pending automatic cliques do not count: the answer
    replaces them.

    Examples
    --------
    >>> from ursim_core.correspondences import Clique
    >>> review = [Clique(id=1, sketch_regions=(1,), metric_regions=(1,), source="manual"),
    ...           Clique(id=2, sketch_regions=(2,), metric_regions=(2,), source="auto", status="rejected")]
    >>> pairs_beside_review([(1, 1), (1, 3), (2, 2), (2, 4), (2, 4)], review)
    [(2, 4)]
    """
    return allowed_pairs(pairs, constraints_from_cliques(cliques))
