"""The values of a match: :class:`Prepared` (everything that does not depend on m) and :class:`MatchResult`."""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field
from typing import Any

import networkx as nx
import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.matching.config import MatchConfig
from ursim_core.matching.constraints import IndexConstraints, MatchConstraints, index_constraints
from ursim_core.matching.descriptors import PairDescriptors
from ursim_core.matching.planar import PlanarGraph

__all__ = [
    "Prepared",
    "MatchResult",
    "replaced",
    "new_result",
    "match_record",
    "next_reading_record",
    "readings_record",
    "laid_by",
]


@dataclass(frozen=True, eq=False)
class Prepared:
    """Everything of a map pair that does not depend on m (see :func:`prepare`).

    Examples
    --------
    >>> from ursim_core.matching.pipeline import match_prepared, prepare
    >>> g = nx.cycle_graph(4)  # four rooms around a courtyard
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> prepared = prepare(g, g.copy())  # orientation unknown: the candidate orientations are tried
    >>> prepared.orientation, len(prepared.orientation_scan), prepared.c_matrix.shape
    ((0.0, False), 4, (4, 4))
    >>> sorted(match_prepared(prepared, 0.1).pairs)  # matched at any m without preparing again
    [(0, 0), (1, 1), (2, 2), (3, 3)]
    """

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
    #: What a person has said about the pair (:class:`~ursim_core.matching.constraints.MatchConstraints`).
    constraints: MatchConstraints | None = None
    #: The sketch's other segmentations, prepared (:class:`~ursim_core.matching.resampling.Resampled`):
    #: :func:`match_prepared` votes over their answers.
    resampled: Any = None
    #: The free-space overlap of every candidate orientation that was measured, ``{(degrees, mirrored):
    #: overlap}``; the sketch's other segmentations take theirs from it (see ``oriented.carried_by_orientation``).
    orientation_overlaps: dict = field(default_factory=dict)
    #: With ``MatchConfig.window_reading_margin``: each finalist orientation's best window,
    #: ``{(degrees, mirrored): (correlation, gain) or None}``, carried to the other segmentations.
    orientation_windows: dict = field(default_factory=dict)
    #: With ``MatchConfig.window_start``: each finalist orientation's laying of the sketch's positions
    #: in its best window, a scale and shift per axis (``refit`` transform) or None, carried to the
    #: other segmentations.
    orientation_window_starts: dict = field(default_factory=dict)
    #: The two maps' label images, for ``MatchConfig.elastic`` (set by :func:`prepare` when it is
    #: given segmentations), and its answers by orientation (the flow does not depend on m).
    sketch_labels: Any = None
    metric_labels: Any = None
    elastic_answers: dict = field(default_factory=dict)

    @functools.cached_property
    def index_constraints(self) -> IndexConstraints | None:
        """``constraints`` in the planar graphs' vertex indices (None when there are none)."""
        return index_constraints(self.constraints, self.sketch_planar.nodes, self.metric_planar.nodes)

    @functools.cached_property
    def answer_fields(self) -> dict:
        """The fields every :class:`MatchResult` of this preparation shares (its anchors, unique
        regions, signatures, c, options and orientation), for ``single._result``."""
        descriptors = self.descriptors
        signatures = None
        if descriptors is not None and descriptors.sketch_signatures is not None:
            signatures = (descriptors.sketch_signatures, descriptors.metric_signatures)
        return {
            "anchors": list(descriptors.anchors) if descriptors else [],
            "unique_sketch": list(descriptors.unique_sketch) if descriptors else [],
            "unique_metric": list(descriptors.unique_metric) if descriptors else [],
            "signatures": signatures,
            "c_matrix": self.c_matrix,
            "config": self.config,
            "orientation": self.orientation,
            "orientation_scan": self.orientation_scan,
            "resampling_votes": 0,
            "laid": False,
            "laying": None,
        }

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
    resampling_votes : int
        How many segmentations of a resampled sketch voted on ``pairs``
        (:mod:`ursim_core.matching.resampling`; the other fields are the first segmentation's
        answer's); 0 when there was no vote.
    laid : bool
        The pairs are those of the sketch laid on the metric map and bent onto it
        (``MatchConfig.elastic``, :mod:`ursim_core.matching.elastic`); ``m``, the cost and the
        orientation are the planar matcher's, which read the orientation.
    laying : Laying or None
        With ``laid``: how the sketch was laid on the metric map before it was bent
        (:class:`~ursim_core.matching.layings.Laying`: box onto box, or fitted to the planar
        answer's pairs; ``MatchConfig.elastic_laying``), to draw it again; None otherwise.

    Examples
    --------
    The repr shows the answer; ``signatures``, ``c_matrix``, ``config``, ``m_scan`` and
    ``orientation_scan`` are left out of it (read them as attributes):

    >>> result = MatchResult([(1, 2)], [], [], [], 0.1, 3.0, 0.2, None, np.zeros((40, 40)), 1, 1, "", MatchConfig())
    >>> repr(result)[:60]
    'MatchResult(pairs=[(1, 2)], anchors=[], unique_sketch=[], un'
    >>> "c_matrix" in repr(result), result.c_matrix.shape
    (False, (40, 40))
    """

    # repr=False: the signatures, c, the scans and the configuration made a repr of ~7,500
    # characters that buried the answer (pairs, m, cost, reason); they stay attributes.
    pairs: list
    anchors: list
    unique_sketch: list
    unique_metric: list
    m: float
    cost: float
    normalised_cost: float
    signatures: tuple | None = field(repr=False)
    c_matrix: np.ndarray = field(repr=False)
    seeds_count: int
    hypotheses: int
    reason: str
    config: MatchConfig = field(repr=False)
    m_scan: dict = field(default_factory=dict, repr=False)
    orientation: tuple = (0.0, False)
    orientation_scan: dict = field(default_factory=dict, repr=False)
    resampling_votes: int = 0
    laid: bool = False
    laying: Any = None


_RESULT_FIELDS = frozenset(f.name for f in dataclasses.fields(MatchResult))


def replaced(result: MatchResult, **changes) -> MatchResult:
    """``dataclasses.replace(result, **changes)`` without calling ``__init__``: the same fields
    (unchanged ones the same objects), at a tenth of the cost.

    A turned KTH sketch makes several hundred results and copies of results (every m of every
    orientation of six segmentations), and the frozen dataclass's ``__init__`` (a guarded
    ``setattr`` per field) was most of their cost. :class:`MatchResult` computes nothing at init
    and caches nothing, so copying its fields is what ``replace`` would do.

    Examples
    --------
    >>> result = MatchResult([(1, 2)], [], [], [], 0.1, 3.0, 0.2, None, np.zeros((1, 1)), 1, 1, "", MatchConfig())
    >>> moved = replaced(result, m=0.2)
    >>> moved.m, moved.pairs is result.pairs, result.m
    (0.2, True, 0.1)
    """
    unknown = changes.keys() - _RESULT_FIELDS
    if unknown:
        raise TypeError(f"MatchResult has no field {sorted(unknown)[0]!r}")
    copy = object.__new__(MatchResult)
    copy.__dict__.update(result.__dict__)
    copy.__dict__.update(changes)
    return copy


def new_result(fields: dict) -> MatchResult:
    """``MatchResult(**fields)`` without calling ``__init__`` (see :func:`replaced`); ``fields``
    must name every field (a missing one would be an attribute error later, not here)."""
    if fields.keys() != _RESULT_FIELDS:
        raise TypeError(f"a MatchResult's fields are {sorted(_RESULT_FIELDS)}, not {sorted(fields)}")
    result = object.__new__(MatchResult)
    result.__dict__.update(fields)
    return result


def match_record(config: MatchConfig, result: MatchResult) -> dict[str, Any]:
    """What produced a file's automatic cliques, JSON-safe: the record ``ursim match`` and the app
    keep in a correspondence file under ``matcher`` (an unknown key to the format, written back).

    ``orientation`` is how the sketch was turned to match; with ``config.orientation == 'any'``
    the matcher chose it, and a reader can offer it as the sketch's orientation.

    Examples
    --------
    >>> result = MatchResult([(1, 2)], [], [], [], 0.1, 3.0, 0.2, None, np.zeros((1, 1)), 1, 1, "",
    ...                      MatchConfig(), orientation=(180.0, False))
    >>> record = match_record(result.config, result)
    >>> record["config"]["orientation"], record["orientation"]
    ('any', {'degrees': 180.0, 'mirrored': False})
    """
    import dataclasses
    import json
    import math

    def safe(value: Any) -> Any:
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    return {
        "config": json.loads(json.dumps(dataclasses.asdict(config), default=str)),
        "m": safe(float(result.m)) if result.m is not None else None,
        "cost": safe(float(result.cost)) if result.cost is not None else None,
        "anchors": [[int(a), int(b)] for a, b in result.anchors],
        "reason": result.reason or "",
        # How the sketch was turned to match (chosen when config.orientation is 'any').
        "orientation": {"degrees": round(float(result.orientation[0]), 6), "mirrored": bool(result.orientation[1])},
        # Whether the pairs are the laid sketch's (MatchConfig.elastic) or the matcher's own.
        "pairs_from": "laid sketch" if result.laid else "matcher",
        # How the sketch was laid before it was bent: box onto box, or by the planar answer's pairs.
        **({"laid_by": laid_by(result)} if laid_by(result) else {}),
        **next_reading_record(result),
        **readings_record(result),
    }


def laid_by(result: MatchResult) -> str:
    """How a laid answer's sketch was laid before it was bent: ``"boxes"`` (box onto box) or
    ``"answer"`` (by the planar answer's pairs) or ``"window"`` (in the window of the metric map it
    correlates with best; both ``MatchConfig.elastic_laying``); ``""`` when the
    pairs are not the laid sketch's."""
    laying = getattr(result, "laying", None)
    return laying.by if getattr(result, "laid", False) and laying is not None else ""


def next_reading_record(result: MatchResult) -> dict[str, Any]:
    """``{"next_reading": {"degrees", "mirrored", "ranked_worse_by"}}``: the reading the matcher ranked
    next when it chose the orientation (:func:`~ursim_core.matching.orientation.next_reading`),
    JSON-safe; empty when there is none (the orientation was told, or one reading was tried).

    Examples
    --------
    >>> result = MatchResult([], [], [], [], 0.1, 3.0, 0.2, None, np.zeros((1, 1)), 1, 1, "", MatchConfig(),
    ...                      orientation=(0.0, False), orientation_scan={(0.0, False): 0.4, (180.0, True): 0.5})
    >>> next_reading_record(result)
    {'next_reading': {'degrees': 180.0, 'mirrored': True, 'ranked_worse_by': 0.25}}
    """
    import math

    from ursim_core.matching.orientation import next_reading

    found = next_reading(result.orientation, result.orientation_scan) if result.orientation_scan else None
    if found is None or not math.isfinite(found[1]):
        return {}
    (degrees, mirrored), gap = found
    return {"next_reading": {"degrees": round(degrees, 6), "mirrored": mirrored, "ranked_worse_by": round(gap, 6)}}


def readings_record(result: MatchResult) -> dict[str, Any]:
    """``{"readings": [{"degrees", "mirrored", "ranked_worse_by"}, ...]}``: every reading the matcher
    ranked when it chose the orientation, its own first
    (:func:`~ursim_core.matching.orientation.ranked_readings`), JSON-safe; empty when there is no
    other (the orientation was told, or one reading was tried). The app offers them side by side
    to be matched in.

    Examples
    --------
    >>> result = MatchResult([], [], [], [], 0.1, 3.0, 0.2, None, np.zeros((1, 1)), 1, 1, "", MatchConfig(),
    ...                      orientation=(0.0, False), orientation_scan={(0.0, False): 0.4, (180.0, True): 0.5})
    >>> [reading["ranked_worse_by"] for reading in readings_record(result)["readings"]]
    [0.0, 0.25]
    """
    from ursim_core.matching.orientation import ranked_readings

    ranked = ranked_readings(result.orientation, result.orientation_scan) if result.orientation_scan else []
    if len(ranked) < 2:
        return {}
    return {
        "readings": [
            {"degrees": round(degrees, 6), "mirrored": mirrored, "ranked_worse_by": round(gap, 6)}
            for (degrees, mirrored), gap in ranked
        ]
    }


def require_segmentations(sketch_seg: Any, metric_seg: Any) -> None:
    """Refuse what :func:`~ursim_core.matching.pipeline.match` cannot take, naming the argument:
    a map (``match(Map, Map)`` gave ``AttributeError: 'Map' object has no attribute 'graph'``),
    an array, a path.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> require_segmentations(map_from_array(np.full((4, 4), 255, np.uint8)), None)
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: field 'sketch_seg': must be a Segmentation or a region graph, got Map: ...
    """
    for name, value in (("sketch_seg", sketch_seg), ("metric_seg", metric_seg)):
        if hasattr(value, "graph") or (hasattr(value, "nodes") and hasattr(value, "edges")):
            continue
        hint = ": segment it first (ursim_core.matching.match_maps matches two maps)" if hasattr(value, "free") else ""
        raise ParameterError(f"must be a Segmentation or a region graph, got {type(value).__name__}{hint}", field=name)
