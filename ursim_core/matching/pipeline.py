"""URSIM matching of a sketch segmentation to a metric segmentation.

Entry point: :func:`match` ``(sketch_seg, metric_seg, *, config=MatchConfig()) -> MatchResult``.
For sweeping m, :func:`prepare` computes everything that does not depend on m once (attributes,
anchors, weights, signatures, the ``c`` matrix, neighbour orders) and :func:`match_prepared` runs
one matcher at one m.

Configuration (:class:`MatchConfig`): every departure of the released C++ code and every extension
beyond the paper is a named option, so each can be measured. :meth:`MatchConfig.paper` is the
paper's method as published, :meth:`MatchConfig.released` turns every released-code option on, and
the default ``MatchConfig()`` is the paper's method plus the two extensions that the KTH evidence
supports (position-aware comparison, signature-aware hypothesis score) and the automatic m.
See ``ursim_core.matching.descriptors`` (signatures), ``ursim_core.matching.planar`` (Algorithm 1),
``ursim_core.matching.baselines`` (Hungarian, VF2), ``ursim_core.matching.auto_m`` (the automatic
choice of m, with the evidence for the defaults) and ``ursim_core.evaluation.kth_protocol`` (the KTH
evaluation protocol).

Segmentation for matching: the evidence was gathered with MAORIS preset ``"default"`` (t = 0.25,
doors 40; the parameters the KTH ground truth was clicked on) for both maps, binarised at > 250.
The ``"sketch"`` preset (t = 0.30, doors 60) splits the sketches more and matched worse (paper T4,
oracle m: 0.51 against 0.665 mean F1).

Degenerate inputs (an empty graph, a single region, no unique region, no anchor, no seed,
disconnected graphs, constant attributes) never raise: the result is valid, possibly empty, and its
``reason`` says what was degenerate.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import networkx as nx
import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.matching.baselines import hungarian_match, vf2_match
from ursim_core.matching.descriptors import (
    DEFAULT_TIMES,
    SIZE_WEIGHT_FLOOR,
    VARIANTS,
    PairDescriptors,
    blend_positions,
    pair_descriptors,
)
from ursim_core.matching.orientation import ORIENTATIONS, orientation_candidates, oriented_graph
from ursim_core.matching.planar import PlanarGraph, planar_graph, planar_match
from ursim_core.segmentation.canonical import wall_angle

#: MAORIS preset used for both maps when matching. Measured on the 18 KTH sketches (planar T4,
#: automatic m, mean F1 malcolm/vasiliki): default/default .627/.692, icra/icra .598/.662,
#: sketch/default .571/.607, default/robot .509/.551, sketch/robot .458/.499. The annotators'
#: ground truth was also clicked on this preset (original_code.md §2.9).
MATCH_PRESETS = {"sketch": "default", "metric": "default"}

__all__ = [
    "MATCH_PRESETS",
    "M_GRID",
    "MatchConfig",
    "MatchResult",
    "Prepared",
    "prepare",
    "match_prepared",
    "match",
    "seed_pairs",
    "seed_cap",
    "pair_cost_matrix",
]

#: The released driver's sweep: 0, 0.025, ..., 0.475 (20 values).
M_GRID = tuple(round(0.025 * i, 10) for i in range(20))
MATCHERS = ("planar", "hungarian", "vf2")


@dataclass(frozen=True, kw_only=True)
class MatchConfig:
    """Options of the matcher; the defaults are the recommended configuration.

    Attributes
    ----------
    variant : {'T4', 'T1', 'T2', 'T3', 'baseline'}
        Descriptor variant (paper Table 1): T4 = URSIM (anchors + weights).
    matcher : {'planar', 'hungarian', 'vf2'}
    m : 'auto' or float
        Threshold on ``c`` below which two regions are "the same". ``'auto'`` picks it
        per map pair over ``m_grid`` (:mod:`ursim_core.matching.auto_m`).
    times : tuple of float
        Heat-kernel sample times.
    uniqueness_k : float
        A region is unique when ``|z| >= k`` on an attribute.
    standardise : {'own', 'model'}
        Statistics for the sketch's z-scores (released code: 'model').
    weights : {'size', 'uniqueness', 'equal'} or None
        Vertex weights; None derives them from the variant (T1/T2 equal, T3/T4 size).
        The released code used 'uniqueness' for T4.
    disparity : {'paper', 'released'}
        Anchor disparity.
    rotation_search : {'min', 'first'}
        Seed neighbour alignment over rotations (released code: 'first', a bug).
    reflections : bool
        Also try mirrored neighbour orders at the seed (not in the released code).
    size_weight_floor : float
        Added to ``z_size - min z_size`` for the size weights.
    m_grid : tuple of float
        Values of m considered by ``m='auto'``.
    auto_rule : str
        Rule used by ``m='auto'`` (see :mod:`ursim_core.matching.auto_m`).
    max_seeds : int, 'auto' or None
        Cap on the number of seeds (the lowest-c ones are kept, in their original
        order). ``'auto'`` = ``max(64, 100_000 // max(n1, n2))``: each expansion costs
        O(n), so this bounds the planar matcher to about 1e5 expanded pairs on large
        graphs; it never binds on sketch-sized graphs (6666 seeds for 15 regions,
        while 15 x 15 = 225 pairs exist). None = no cap.
    vf2_timeout : float
        Wall-clock budget of the VF2 baseline, seconds.
    signature_method : {'auto', 'eigh', 'expm'}
    position_weight : float
        beta in ``c = (c_signature + beta * d_position) / (1 + beta)`` (0 = paper); see
        :mod:`ursim_core.matching.descriptors`. Assumes the sketch keeps the map's orientation.
    hypothesis_score : {'signature', 'substitutions', 'structure'}
        Planar hypothesis score: 'structure' = the released code's structural cost;
        'substitutions' = plus ``score_weight`` per matched pair with ``c > m`` (the
        paper's "replace: 1"); 'signature' = plus ``score_weight * sum of c`` over the
        matched pairs. Also used to score Hungarian and VF2 results.
    score_weight : float
        Weight of the pair term of the hypothesis score.
    orientation : 'any', 'upright' or float
        How the sketch is turned relative to the metric map. 'any' (default): unknown; the
        matcher tries the turns that bring the sketch's walls parallel to the metric map's
        (4 quarter turns of the wall-angle difference) and keeps the lowest-scoring answer
        (:mod:`ursim_core.matching.orientation`). 'upright': drawn in the metric map's
        orientation. A number: the sketch is brought to the metric map by turning it that
        many degrees counter-clockwise (after mirroring when ``mirrored``).
    mirrored : bool or None
        Whether the sketch is a left-right mirror image of the map; None (default) = unknown,
        both are tried with ``orientation='any'`` (with 'upright' or a number, None = no).
    """

    variant: str = "T4"
    matcher: str = "planar"
    m: Any = "auto"
    times: tuple = DEFAULT_TIMES
    uniqueness_k: float = 1.0
    standardise: str = "own"
    weights: str | None = None
    disparity: str = "paper"
    rotation_search: str = "min"
    reflections: bool = False
    size_weight_floor: float = SIZE_WEIGHT_FLOOR
    m_grid: tuple = M_GRID
    auto_rule: str = "score"
    max_seeds: Any = "auto"
    vf2_timeout: float = 2.0
    signature_method: str = "auto"
    position_weight: float = 2.0
    hypothesis_score: str = "signature"
    score_weight: float = 8.0
    orientation: Any = "any"
    mirrored: bool | None = None

    def __post_init__(self):
        choices = {
            "variant": VARIANTS,
            "matcher": MATCHERS,
            "standardise": ("own", "model"),
            "weights": (None, "size", "uniqueness", "equal"),
            "disparity": ("paper", "released"),
            "rotation_search": ("min", "first"),
            "signature_method": ("auto", "eigh", "expm"),
            "hypothesis_score": ("signature", "substitutions", "structure"),
        }
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ParameterError(f"must be one of {allowed}, not {getattr(self, name)!r}", field=name)
        if self.m != "auto":
            if (
                isinstance(self.m, bool)
                or not isinstance(self.m, (int, float))
                or not math.isfinite(self.m)
                or self.m < 0
            ):
                raise ParameterError(f"must be 'auto' or a non-negative number, not {self.m!r}", field="m")
        if self.max_seeds not in ("auto", None) and (not isinstance(self.max_seeds, int) or self.max_seeds < 1):
            raise ParameterError(
                f"must be 'auto', None or a positive integer, not {self.max_seeds!r}", field="max_seeds"
            )
        for name in ("position_weight", "score_weight", "uniqueness_k", "size_weight_floor", "vf2_timeout"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
                raise ParameterError(f"must be a non-negative number, not {value!r}", field=name)
        if self.orientation not in ORIENTATIONS and (
            isinstance(self.orientation, bool)
            or not isinstance(self.orientation, (int, float))
            or not math.isfinite(self.orientation)
        ):
            raise ParameterError(
                f"must be 'any', 'upright' or a number of degrees, not {self.orientation!r}", field="orientation"
            )
        if self.mirrored not in (None, True, False):
            raise ParameterError(f"must be true, false or null, not {self.mirrored!r}", field="mirrored")
        if not self.times:
            raise ParameterError("needs at least one time", field="times")
        if not self.m_grid:
            raise ParameterError("needs at least one value", field="m_grid")
        from ursim_core.matching.auto_m import AUTO_RULES

        if self.auto_rule not in AUTO_RULES:
            raise ParameterError(f"must be one of {tuple(AUTO_RULES)}, not {self.auto_rule!r}", field="auto_rule")

    @classmethod
    def released(cls, **overrides) -> MatchConfig:
        """Every option of the released C++ code on (original_code.md §1.14).

        Sketch standardised with the metric map's statistics, uniqueness-score weights,
        released anchor disparity, first-rotation behaviour, no reflections, m = 0.125
        (its best single fixed m on the KTH sketches). Segmentation options (robot
        parameters for sketches, non-zero-is-free binarisation) belong to the caller.

        Examples
        --------
        >>> MatchConfig.released().weights
        'uniqueness'
        """
        values = dict(
            variant="T4",
            matcher="planar",
            m=0.125,
            standardise="model",
            weights="uniqueness",
            disparity="released",
            rotation_search="first",
            reflections=False,
            position_weight=0.0,
            hypothesis_score="structure",
            score_weight=0.0,
            orientation="upright",
            mirrored=False,
        )
        values.update(overrides)
        return cls(**values)

    @classmethod
    def paper(cls, **overrides) -> MatchConfig:
        """The method as the paper describes it.

        Own-map standardisation, standardised sizes as weights, mean-|dz| disparity,
        minimum-distance rotation, no position term, hypothesis score = structural cost
        plus 1 per substituted pair (the paper's edit costs), m = 0.15 (the paper's best
        fixed m, Section 6.4).

        Examples
        --------
        >>> MatchConfig.paper().position_weight, MatchConfig.paper().hypothesis_score
        (0.0, 'substitutions')
        """
        values = dict(
            variant="T4",
            matcher="planar",
            m=0.15,
            standardise="own",
            weights=None,
            disparity="paper",
            rotation_search="min",
            reflections=False,
            position_weight=0.0,
            hypothesis_score="substitutions",
            score_weight=1.0,
            orientation="upright",
            mirrored=False,
        )
        values.update(overrides)
        return cls(**values)

    def replace(self, **changes) -> MatchConfig:
        """A copy with some fields changed (validated like a new config).

        Examples
        --------
        >>> MatchConfig().replace(m=0.2).m
        0.2
        """
        return dataclasses.replace(self, **changes)

    @property
    def effective_weights(self) -> str | None:
        """The weights actually used (None for the baseline variant)."""
        if self.variant == "baseline":
            return None
        if self.weights is not None:
            return self.weights
        return {"T1": "equal", "T2": "equal", "T3": "size", "T4": "size"}[self.variant]


@dataclass(frozen=True, eq=False)
class Prepared:
    """Everything of a map pair that does not depend on m (see :func:`prepare`)."""

    config: MatchConfig
    sketch_graph: nx.Graph
    metric_graph: nx.Graph
    descriptors: PairDescriptors | None
    sketch_planar: PlanarGraph
    metric_planar: PlanarGraph
    notes: tuple = ()
    #: ``(degrees, mirrored)`` applied to the sketch's positions (see ``MatchConfig.orientation``).
    orientation: tuple = (0.0, False)
    #: For ``orientation='any'``: the score of every candidate tried, ``{(degrees, mirrored): score}``.
    orientation_scan: dict = field(default_factory=dict)
    #: The automatic-m answer found while choosing the orientation (reused by :func:`match_prepared`).
    chosen: Any = None

    @property
    def c_matrix(self) -> np.ndarray:
        if self.descriptors is None:
            return np.zeros((self.sketch_planar.n_vertices, self.metric_planar.n_vertices))
        return self.descriptors.c_matrix


@dataclass(frozen=True, eq=False)
class MatchResult:
    """Correspondences found between a sketch and a metric map.

    Attributes
    ----------
    pairs : list of (sketch_region, metric_region)
    anchors : list of (sketch_region, metric_region)
        Hungarian pairs of unique regions used as heat sources.
    unique_sketch, unique_metric : list
        Unique regions of each map.
    m : float
        The threshold used (the chosen one when ``config.m == 'auto'``).
    cost : float
        Planar hypothesis cost of the answer (``inf`` when nothing was matched; for the
        Hungarian and VF2 matchers the same cost formula applied to their pairs).
    normalised_cost : float
        ``cost / (n1 + n2 + e1 + e2)``: 1 when nothing is matched, 0 for a perfect match.
    signatures : tuple of ndarray or None
        (sketch, metric) signatures, rows in ascending region-id order.
    c_matrix : ndarray
        ``c`` for every (sketch, metric) pair, rows/columns in ascending region-id order.
    seeds_count : int
        Pairs with ``c <= m`` used as seeds (after the ``max_seeds`` cap).
    hypotheses : int
        Hypotheses scored by the planar matcher.
    reason : str
        Non-empty when the input or the result is degenerate.
    config : MatchConfig
    m_scan : dict
        For ``m='auto'``: the statistic of the rule for each m of the grid.
    orientation : (float, bool)
        The turn (degrees counter-clockwise) and mirroring that brought the sketch to the
        metric map, chosen or given (``MatchConfig.orientation``).
    orientation_scan : dict
        With ``orientation='any'``: the normalised score of each candidate tried.
    """

    pairs: list
    anchors: list
    unique_sketch: list
    unique_metric: list
    m: float
    cost: float
    normalised_cost: float
    signatures: tuple | None
    c_matrix: np.ndarray
    seeds_count: int
    hypotheses: int
    reason: str
    config: MatchConfig
    m_scan: dict = field(default_factory=dict)
    orientation: tuple = (0.0, False)
    orientation_scan: dict = field(default_factory=dict)


def _graph_of(segmentation_or_graph) -> nx.Graph:
    if isinstance(segmentation_or_graph, nx.Graph):
        return segmentation_or_graph
    return segmentation_or_graph.graph


def prepare(sketch_seg, metric_seg, config: MatchConfig = MatchConfig(), *, progress=None) -> Prepared:
    """Compute everything that does not depend on m, the sketch's orientation included.

    With ``config.orientation='any'`` (the default) every candidate orientation of
    :func:`ursim_core.matching.orientation.orientation_candidates` is matched with the
    configured m (the automatic m by default) and the one whose answer scores lowest is kept;
    ties go to the earlier candidate, the identity first. The signatures are computed once:
    only the position term and the neighbour orders depend on the orientation.

    Parameters
    ----------
    sketch_seg, metric_seg : Segmentation or networkx.Graph
        Segmentations (their ``.graph`` is used) or region graphs directly.
    config : MatchConfig
    progress : callable, optional
        ``progress(fraction, message)`` while the orientations are tried.

    Examples
    --------
    >>> g = nx.path_graph(3)
    >>> nx.set_node_attributes(g, {0: 50, 1: 10, 2: 12}, "size")
    >>> nx.set_node_attributes(g, 0.3, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    >>> prepare(g, g.copy()).c_matrix.shape
    (3, 3)
    """
    sketch_graph, metric_graph = _graph_of(sketch_seg), _graph_of(metric_seg)
    candidates = _orientations(config, sketch_seg, metric_seg)
    base = _prepare_oriented(sketch_graph, metric_graph, config, candidates[0])
    if len(candidates) == 1:
        return base
    prepared_candidates = [
        base if index == 0 else _reoriented(base, sketch_graph, candidate) for index, candidate in enumerate(candidates)
    ]
    finalists = range(len(candidates))
    if config.m == "auto" and len(candidates) > _FINALISTS and len(config.m_grid) > 2 * _COARSE_STEP:
        # Screen every orientation on a coarse m grid first; only the best few get the full sweep.
        coarse = config.replace(m_grid=tuple(config.m_grid[_COARSE_STEP // 2 :: _COARSE_STEP]))
        screened = [
            (match_prepared(dataclasses.replace(prepared, config=coarse)).normalised_cost, index)
            for index, prepared in enumerate(prepared_candidates)
        ]
        finalists = sorted(index for _, index in sorted(screened)[:_FINALISTS])
    trials = []
    for step, index in enumerate(finalists):
        prepared = prepared_candidates[index]
        result = match_prepared(prepared, progress=_share_of(progress, step, len(finalists)))
        trials.append((result.normalised_cost, index, prepared, result))
    _, _, prepared, result = min(trials, key=lambda trial: (trial[0], trial[1]))
    scan = {candidates[trial[1]]: float(trial[0]) for trial in trials}
    return dataclasses.replace(
        prepared, orientation_scan=scan, chosen=dataclasses.replace(result, orientation_scan=scan)
    )


#: With the automatic m, orientations are screened at every ``_COARSE_STEP``-th m of the grid and
#: the ``_FINALISTS`` best get the full sweep (see :func:`prepare`).
#: Chosen on the 18 KTH sketches (interleaved A/B in one session): step 2 with 3 finalists gave
#: the same F1 as the full sweep of all 8 orientations (0.651) in about half the matcher calls.
_COARSE_STEP = 2
_FINALISTS = 3


def _share_of(progress, index: int, count: int):
    """``progress`` for step ``index`` of ``count``: fractions scaled into its share, messages prefixed."""
    if progress is None:
        return None

    def report(fraction: float, message: str) -> None:
        progress((index + fraction) / count, f"orientation {index + 1} of {count}: {message}")

    return report


def _orientations(config: MatchConfig, sketch_seg, metric_seg) -> list[tuple[float, bool]]:
    """The orientations worth trying: only those that can change the answer."""
    if config.orientation != "any":
        return orientation_candidates(orientation=config.orientation, mirrored=config.mirrored)
    if config.position_weight == 0:
        # Without the position term only a mirror image changes anything (the planar
        # matcher's neighbour orders reverse); the other matchers do not see orientation.
        if config.matcher != "planar" or config.mirrored is not None:
            return [(0.0, bool(config.mirrored))]
        return [(0.0, False), (0.0, True)]
    sketch_labels = getattr(sketch_seg, "labels", None)
    metric_labels = getattr(metric_seg, "labels", None)
    return orientation_candidates(
        orientation="any",
        mirrored=config.mirrored,
        sketch_angle=wall_angle(sketch_labels) if sketch_labels is not None else 0.0,
        metric_angle=wall_angle(metric_labels) if metric_labels is not None else 0.0,
    )


def _reoriented(base: Prepared, sketch_graph: nx.Graph, orientation: tuple[float, bool]) -> Prepared:
    """``base`` for another orientation of the sketch: new positions, same signatures."""
    turned = oriented_graph(sketch_graph, degrees=orientation[0], mirrored=orientation[1])
    descriptors = base.descriptors
    if descriptors is not None and descriptors.signature_c is not None:
        c_matrix = blend_positions(
            descriptors.signature_c,
            turned,
            descriptors.sketch_nodes,
            base.metric_graph,
            descriptors.metric_nodes,
            base.config.position_weight,
        )
        descriptors = dataclasses.replace(descriptors, c_matrix=c_matrix)
    return dataclasses.replace(
        base, sketch_graph=turned, descriptors=descriptors, sketch_planar=planar_graph(turned), orientation=orientation
    )


def _prepare_oriented(sketch_graph, metric_graph, config: MatchConfig, orientation: tuple[float, bool]) -> Prepared:
    sketch_graph = oriented_graph(sketch_graph, degrees=orientation[0], mirrored=orientation[1])
    notes = []
    for name, graph in (("sketch", sketch_graph), ("metric map", metric_graph)):
        count = graph.number_of_nodes()
        if count == 0:
            notes.append(f"the {name} has no regions")
        elif count == 1:
            notes.append(f"the {name} has a single region")
        else:
            components = nx.number_connected_components(graph)
            if components > 1:
                notes.append(f"the {name} graph has {components} connected components (no heat flows between them)")
    descriptors = None
    if sketch_graph.number_of_nodes() and metric_graph.number_of_nodes():
        descriptors = pair_descriptors(
            sketch_graph,
            metric_graph,
            variant=config.variant,
            weights=config.weights,
            standardise_with=config.standardise,
            uniqueness_k=config.uniqueness_k,
            disparity=config.disparity,
            times=config.times,
            size_weight_floor=config.size_weight_floor,
            method=config.signature_method,
            position_weight=config.position_weight,
        )
        notes.extend(descriptors.notes)
        if config.variant != "baseline" and not descriptors.unique_sketch and not descriptors.unique_metric:
            notes.append("no unique region in either map")
    return Prepared(
        config=config,
        sketch_graph=sketch_graph,
        metric_graph=metric_graph,
        descriptors=descriptors,
        sketch_planar=planar_graph(sketch_graph),
        metric_planar=planar_graph(metric_graph),
        notes=tuple(dict.fromkeys(notes)),
        orientation=orientation,
    )


def seed_pairs(c_matrix: np.ndarray, m: float, *, max_seeds: int | None = None) -> list[tuple[int, int]]:
    """All index pairs with ``c <= m``, sketch outer loop, metric inner loop.

    With ``max_seeds``, only the ``max_seeds`` pairs of lowest c are kept (ties by order),
    still returned in loop order.

    Examples
    --------
    >>> seed_pairs(np.array([[0.0, 0.2], [0.1, 0.5]]), 0.2)
    [(0, 0), (0, 1), (1, 0)]
    >>> seed_pairs(np.array([[0.0, 0.2], [0.1, 0.5]]), 0.2, max_seeds=2)
    [(0, 0), (1, 0)]
    """
    c_matrix = np.asarray(c_matrix)
    rows, cols = np.nonzero(c_matrix <= m)
    if max_seeds is not None and rows.size > max_seeds:
        keep = np.sort(np.argsort(c_matrix[rows, cols], kind="stable")[:max_seeds])
        rows, cols = rows[keep], cols[keep]
    return list(zip(rows.tolist(), cols.tolist()))


def seed_cap(max_seeds, n_sketch: int, n_metric: int) -> int | None:
    """Resolve ``MatchConfig.max_seeds`` for graphs of the given sizes.

    Examples
    --------
    >>> seed_cap("auto", 15, 8), seed_cap("auto", 1000, 1000), seed_cap(None, 5, 5)
    (6666, 100, None)
    """
    if max_seeds == "auto":
        return max(64, 100_000 // max(1, n_sketch, n_metric))
    return max_seeds


def pair_cost_matrix(config: MatchConfig, c_matrix: np.ndarray, m: float) -> np.ndarray | None:
    """Per-pair term of the hypothesis score for ``config.hypothesis_score`` (None for 'structure').

    Examples
    --------
    >>> pair_cost_matrix(MatchConfig(hypothesis_score="substitutions"), np.array([[0.1, 0.3]]), 0.2).tolist()
    [[0.0, 1.0]]
    """
    if config.hypothesis_score == "structure" or config.score_weight == 0:
        return None
    if config.hypothesis_score == "substitutions":
        return (np.asarray(c_matrix) > m).astype(np.float64)
    return np.asarray(c_matrix, dtype=np.float64)


def _cost_of(prepared: Prepared, index_pairs, pair_costs) -> tuple[float, float]:
    first, second = prepared.sketch_planar, prepared.metric_planar
    total = first.n_vertices + second.n_vertices + len(first.edges) + len(second.edges)
    if not index_pairs:
        return math.inf, 1.0
    from ursim_core.matching.planar import hypothesis_cost

    cost = float(hypothesis_cost(first, second, index_pairs))
    if pair_costs is not None:
        cost += prepared.config.score_weight * float(sum(pair_costs[i, j] for i, j in index_pairs))
    return cost, (cost / total if total else 0.0)


def match_prepared(prepared: Prepared, m: float | None = None, *, progress=None) -> MatchResult:
    """Run the configured matcher at one m (or the automatic m when ``m`` is None and
    the config says ``'auto'``).

    ``progress(fraction, message)``, when given, follows the automatic m's sweep.

    Examples
    --------
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> sorted(match_prepared(prepare(g, g.copy()), 0.01).pairs)
    [(0, 0), (1, 1), (2, 2), (3, 3)]
    """
    config = prepared.config
    if m is None and prepared.chosen is not None:
        return prepared.chosen
    if m is None:
        if config.m == "auto":
            from ursim_core.matching.auto_m import choose_m

            return choose_m(prepared, progress=progress)
        m = float(config.m)
    m = float(m)
    descriptors = prepared.descriptors
    c_matrix = prepared.c_matrix
    reasons = list(prepared.notes)
    anchors = list(descriptors.anchors) if descriptors else []
    unique_sketch = list(descriptors.unique_sketch) if descriptors else []
    unique_metric = list(descriptors.unique_metric) if descriptors else []
    signatures = None
    if descriptors is not None and descriptors.sketch_signatures is not None:
        signatures = (descriptors.sketch_signatures, descriptors.metric_signatures)
    if config.variant in ("T2", "T4") and descriptors is not None and not anchors:
        reasons.append("no anchors: anchor signatures are all zero, matching is structural only")
    index_pairs: list = []
    seeds_count = 0
    hypotheses = 0
    pair_costs = pair_cost_matrix(config, c_matrix, m) if descriptors is not None else None
    if descriptors is not None:
        if config.matcher == "planar":
            seeds = seed_pairs(c_matrix, m, max_seeds=seed_cap(config.max_seeds, *c_matrix.shape))
            seeds_count = len(seeds)
            if not seeds:
                reasons.append(f"no seeds: no pair of regions has c <= m = {m:g}")
            else:
                same = (c_matrix <= m).tolist()
                outcome = planar_match(
                    prepared.sketch_planar,
                    prepared.metric_planar,
                    same,
                    seeds=seeds,
                    rotation_search=config.rotation_search,
                    reflections=config.reflections,
                    pair_costs=None if pair_costs is None else pair_costs.tolist(),
                    pair_cost_weight=config.score_weight,
                )
                index_pairs = outcome.pairs
                hypotheses = outcome.hypotheses
        elif config.matcher == "hungarian":
            index_pairs = hungarian_match(c_matrix, m)
            if not index_pairs:
                reasons.append(f"no assigned pair has c <= m = {m:g}")
        else:
            sketch_nodes, metric_nodes = prepared.sketch_planar.nodes, prepared.metric_planar.nodes
            found = vf2_match(prepared.sketch_graph, prepared.metric_graph, c_matrix, m, timeout=config.vf2_timeout)
            sketch_index = {n: i for i, n in enumerate(sketch_nodes)}
            metric_index = {n: i for i, n in enumerate(metric_nodes)}
            index_pairs = [(sketch_index[a], metric_index[b]) for a, b in found.pairs]
            if found.gave_up:
                reasons.append(found.gave_up)
            elif not index_pairs:
                reasons.append(f"no subgraph isomorphism with c <= m = {m:g}")
    cost, normalised = _cost_of(prepared, index_pairs, pair_costs)
    sketch_nodes, metric_nodes = prepared.sketch_planar.nodes, prepared.metric_planar.nodes
    pairs = [(sketch_nodes[i], metric_nodes[j]) for i, j in index_pairs]
    return MatchResult(
        pairs=pairs,
        anchors=anchors,
        unique_sketch=unique_sketch,
        unique_metric=unique_metric,
        m=m,
        cost=cost,
        normalised_cost=normalised,
        signatures=signatures,
        c_matrix=c_matrix,
        seeds_count=seeds_count,
        hypotheses=hypotheses,
        reason="; ".join(dict.fromkeys(reasons)),
        config=config,
        orientation=prepared.orientation,
        orientation_scan=prepared.orientation_scan,
    )


def match(sketch_seg, metric_seg, *, config: MatchConfig = MatchConfig(), progress=None) -> MatchResult:
    """Match the regions of a sketch to the regions of a metric map.

    Parameters
    ----------
    sketch_seg, metric_seg : Segmentation or networkx.Graph
    config : MatchConfig
    progress : callable, optional
        ``progress(fraction, message)`` during the automatic m's sweep.

    Returns
    -------
    MatchResult

    Examples
    --------
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> result = match(g, g.copy())
    >>> sorted(result.pairs), result.reason
    ([(0, 0), (1, 1), (2, 2), (3, 3)], '')
    """
    return match_prepared(prepare(sketch_seg, metric_seg, config, progress=progress), progress=progress)
