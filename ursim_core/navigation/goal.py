"""From a point on the sketch to a goal in the robot's map: :func:`locate`.

The rule is the one of place accuracy (issue 11), so that the score and the robot agree: the
tapped sketch point belongs to the region under it (or the nearest region within 10 px, the
annotators' rule, :func:`~ursim_core.correspondences.regions_at_points`); the goal is the
interior point (the pixel farthest from the region's border) of the *largest* metric region
matched to that sketch region. ``target="mirror"`` instead places the goal where the tap sits
relative to its sketch region, carried over by the similarity that best aligns the matched
region centroids and kept inside the matched metric regions.

:func:`locate` is pure and cheap (one region look-up and a dictionary access; no image-sized
work unless the tap is unmatched and a nearest matched region is asked for), so evaluation code
can call it for every ground-truth point. Build the :class:`MatchTable` once with
:func:`match_table` (given the segmentations, for a correspondence file: its points decide the
regions) and pass it instead of the match when calling it many times.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ursim_core.correspondences import regions_at_points
from ursim_core.correspondences.exporters import LABEL_KEY, clique_label
from ursim_core.errors import ParameterError

__all__ = [
    "interior_target",
    "Goal",
    "NearestMatch",
    "MatchTable",
    "match_table",
    "clique_regions",
    "locate",
    "LABEL_KEY",
    "TARGETS",
    "clique_label",
]

#: Where inside the matched metric region the goal goes.
TARGETS = ("interior", "mirror")


@dataclass(frozen=True)
class MatchTable:
    """Which metric regions each sketch region is matched to, and by which clique.

    Attributes
    ----------
    metric_of : dict
        sketch region -> tuple of metric regions (in match order).
    clique_of : dict
        sketch region -> clique id (correspondence files only).
    label_of : dict
        sketch region -> semantic label of its clique, when it has one.
    pairs : tuple of (int, int)
        Every (sketch, metric) pair, for the mirror target's alignment.

    Examples
    --------
    Made by :func:`match_table`; from a correspondence file, its points decide the regions:

    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :9] = 1; labels[:, 11:] = 2
    >>> kitchen = Clique(id=5, sketch_points=[(4, 3)], metric_points=[(4, 15)], extra={"label": "kitchen"})
    >>> table = match_table(Correspondences(cliques=(kitchen,)), labels, labels)
    >>> table.metric_of, table.clique_of, table.label_of, table.pairs
    ({1: (2,)}, {1: 5}, {1: 'kitchen'}, ((1, 2),))
    """

    metric_of: dict = field(default_factory=dict)
    clique_of: dict = field(default_factory=dict)
    label_of: dict = field(default_factory=dict)
    pairs: tuple = ()


def match_table(match: Any, sketch_seg: Any = None, metric_seg: Any = None, *, tolerance: float = 10) -> MatchTable:
    """Normalise any form of match into a :class:`MatchTable`.

    Parameters
    ----------
    match : MatchResult, Correspondences, MatchTable, mapping or iterable of pairs
        A matcher's result (its ``pairs``); a correspondence file's cliques (every sketch
        region of a clique is matched to every metric region of it; rejected cliques are left
        out; a clique's ``label`` is kept); ``{sketch_region: metric_region(s)}``; or
        ``(sketch_region, metric_region)`` pairs.
    sketch_seg, metric_seg : Segmentation or label array, optional
        The segmentations the table is for. With both, the region ids of cliques come from
        their points (points are authoritative: ids stored in a file may be those of another
        segmentation), as ``ursim goal --correspondences`` does; see :func:`clique_regions`.
        Without them, a clique's stored ids are used as they are.
    tolerance : float, keyword-only
        Pixels from a region within which a clique's point still counts (10, as the annotators).

    Raises
    ------
    SegmentationError
        A label image's shape differs from the map size the correspondence file recorded.

    Warns
    -----
    RegionsRecomputedWarning
        Stored region ids of cliques disagreed with their points in these segmentations.

    Examples
    --------
    >>> table = match_table([(1, 7), (1, 8), (2, 9)])
    >>> table.metric_of
    {1: (7, 8), 2: (9,)}
    """
    if isinstance(match, MatchTable):
        return match
    if hasattr(match, "cliques") and sketch_seg is not None and metric_seg is not None:
        match = clique_regions(match, sketch_seg, metric_seg, tolerance=tolerance)
    metric_of: dict[int, list[int]] = {}
    clique_of: dict[int, int] = {}
    label_of: dict[int, str] = {}
    pairs: list[tuple[int, int]] = []

    def add(sketch: int, metric: int) -> None:
        targets = metric_of.setdefault(int(sketch), [])
        if int(metric) not in targets:
            targets.append(int(metric))
            pairs.append((int(sketch), int(metric)))

    if hasattr(match, "cliques"):
        for clique in match.cliques:
            if clique.effective_status == "rejected":
                continue
            label = clique_label(clique)
            for sketch in clique.sketch_regions:
                for metric in clique.metric_regions:
                    add(sketch, metric)
                if clique.metric_regions:
                    clique_of.setdefault(int(sketch), clique.id)
                    if label is not None:
                        label_of.setdefault(int(sketch), label)
    else:
        items: Iterable = match.pairs if hasattr(match, "pairs") else match
        if isinstance(items, Mapping):
            items = [
                (sketch, metric)
                for sketch, metrics in items.items()
                for metric in (metrics if isinstance(metrics, Iterable) else [metrics])
            ]
        for sketch, metric in items:
            add(sketch, metric)
    return MatchTable(
        metric_of={sketch: tuple(metrics) for sketch, metrics in metric_of.items() if metrics},
        clique_of=clique_of,
        label_of=label_of,
        pairs=tuple(pairs),
    )


def clique_regions(corr: Any, sketch_seg: Any, metric_seg: Any, *, tolerance: float = 10) -> Any:
    """``corr`` with the region ids of its cliques taken from their points in these segmentations.

    :func:`~ursim_core.correspondences.assign_regions` on the cliques that have points; a clique
    with no point at all (made in code from region ids) keeps its ids, since nothing says
    otherwise.

    Parameters
    ----------
    corr : Correspondences
    sketch_seg, metric_seg : Segmentation or (rows, cols) integer array
        The segmentations (their ``labels``) or the label images themselves.
    tolerance : float, keyword-only
        As in :func:`~ursim_core.correspondences.regions_at_points`.

    Examples
    --------
    >>> from ursim_core.correspondences import Clique, Correspondences
    >>> labels = np.array([[1, 1, 0, 2, 2]], dtype=np.int32)
    >>> stale = Correspondences(cliques=(Clique(id=1, sketch_points=[(0, 4)], metric_points=[(0, 0)]),))
    >>> clique_regions(stale, labels, labels).cliques[0].metric_regions
    (1,)
    """
    from ursim_core.correspondences import assign_regions

    sketch_labels = getattr(sketch_seg, "labels", sketch_seg)
    metric_labels = getattr(metric_seg, "labels", metric_seg)
    with_points = [clique for clique in corr.cliques if clique.sketch_points or clique.metric_points]
    if not with_points:
        return corr
    assigned = assign_regions(corr.with_cliques(with_points), sketch_labels, metric_labels, tolerance=tolerance)
    by_id = {clique.id: clique for clique in assigned.cliques}
    return corr.with_cliques(by_id.get(clique.id, clique) for clique in corr.cliques)


@dataclass(frozen=True)
class NearestMatch:
    """The matched sketch region nearest to an unmatched tap (offered instead).

    Examples
    --------
    >>> from ursim_core.segmentation import Segmentation, region_table
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :9] = 1; labels[:, 11:] = 2  # two rooms
    >>> seg = Segmentation(labels, regions=region_table(labels))
    >>> goal = locate([(1, 2)], seg, seg, None, 4, 15)  # a tap in sketch region 2, which is unmatched
    >>> goal.nearest
    NearestMatch(sketch_region=1, point=(4, 8), distance=7.0)
    >>> print(goal.failure_message())
    sketch point (4, 15): sketch region 2 is not matched to any metric region;
    the nearest matched region is 1, at (4, 8), 7.0 px away
    """

    sketch_region: int
    point: tuple[int, int]
    distance: float


@dataclass(frozen=True)
class Goal:
    """Where a sketch point sends the robot.

    Attributes
    ----------
    sketch_point : (row, col)
        The tap, in sketch pixels.
    sketch_region : int
        Its region (0: no region within the tolerance).
    metric_regions : tuple of int
        Every metric region matched to ``sketch_region``.
    metric_region : int or None
        The region the goal lies in.
    pixel : (row, col) or None
        The goal in metric-map pixels; None when unmatched.
    pose : (x, y, yaw) or None
        The goal in world coordinates (metres, radians) when the metric map has a resolution.
    clique_id : int or None
        The clique of the match (correspondence files).
    label : str or None
        The clique's semantic label (room name / type), when it has one.
    reason : str
        Empty on success, else why there is no goal.
    nearest : NearestMatch or None
        For an unmatched tap: the nearest matched sketch region, if any was asked for.

    Examples
    --------
    >>> from ursim_core.io import Map
    >>> from ursim_core.segmentation import Segmentation, region_table
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :9] = 1; labels[:, 11:] = 2  # two rooms
    >>> seg = Segmentation(labels, regions=region_table(labels))
    >>> goal = locate([(1, 2)], seg, seg, Map(free=labels > 0, resolution=0.5), 4, 3)
    >>> goal.ok, goal.sketch_region, goal.metric_region, goal.pixel, goal.pose  # pose: x, y (m), yaw
    (True, 1, 2, (4, 15), (7.75, 2.75, 0.0))
    """

    sketch_point: tuple[int, int]
    sketch_region: int
    metric_regions: tuple[int, ...] = ()
    metric_region: int | None = None
    pixel: tuple[int, int] | None = None
    pose: tuple[float, float, float] | None = None
    clique_id: int | None = None
    label: str | None = None
    reason: str = ""
    nearest: NearestMatch | None = None

    @property
    def ok(self) -> bool:
        """True when the tap gives a goal."""
        return self.pixel is not None

    def failure_message(self) -> str:
        """One line saying why there is no goal, with the nearest matched region when known."""
        row, col = self.sketch_point
        text = f"sketch point ({row}, {col}): {self.reason}"
        if self.nearest is not None:
            near = self.nearest
            text += (
                f"; the nearest matched region is {near.sketch_region}, at ({near.point[0]}, {near.point[1]}), "
                f"{near.distance:.1f} px away"
            )
        return text

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe details (what ``ursim goal`` prints under ``"ursim"``)."""
        return {
            "sketch_point": list(self.sketch_point),
            "sketch_region": self.sketch_region,
            "metric_regions": list(self.metric_regions),
            "metric_region": self.metric_region,
            "pixel": None if self.pixel is None else list(self.pixel),
            "clique": self.clique_id,
            "label": self.label,
            "reason": self.reason,
            "nearest": None
            if self.nearest is None
            else {
                "sketch_region": self.nearest.sketch_region,
                "point": list(self.nearest.point),
                "distance": round(self.nearest.distance, 2),
            },
        }


def interior_target(metric_graph: Any, metric_regions: Any) -> tuple[int, tuple[int, int]]:
    """Where the robot is sent for a sketch region matched to ``metric_regions``.

    The largest of them (pixel count; the smallest id on ties) and its interior point, the pixel
    farthest from its border. Place accuracy (:func:`ursim_core.evaluation.place.place_accuracy`)
    and :func:`locate` both call this, so a goal and the score of goals are one rule.

    Examples
    --------
    >>> import networkx as nx
    >>> g = nx.Graph(); g.add_node(1, size=10, interior=(2, 3)); g.add_node(2, size=40, interior=(8, 9))
    >>> interior_target(g, [1, 2])
    (2, (8, 9))
    """
    chosen = max(metric_regions, key=lambda r: (metric_graph.nodes[r]["size"], -r))
    row, col = metric_graph.nodes[chosen]["interior"]
    return int(chosen), (int(row), int(col))


def locate(
    match: Any,
    sketch_seg: Any,
    metric_seg: Any,
    metric_map: Any,
    row: float,
    col: float,
    *,
    target: str = "interior",
    tolerance: float = 10,
    yaw: float = 0.0,
    suggest_nearest: bool = True,
) -> Goal:
    """The goal in the metric map for the sketch point (row, col).

    Parameters
    ----------
    match : MatchResult, Correspondences, MatchTable, mapping or pairs
        See :func:`match_table`. The region ids of a Correspondences' cliques are taken from
        their points in ``sketch_seg`` and ``metric_seg`` (:func:`clique_regions`), whatever ids
        the file stored. When calling many times, pass the table of
        ``match_table(corr, sketch_seg, metric_seg)`` instead: the assignment is then done once.
    sketch_seg, metric_seg : Segmentation
        The segmentations the match refers to (``labels`` and the region ``graph``).
    metric_map : Map or None
        With a ``resolution`` the goal also gets a world ``pose``. When given, its shape must
        be that of ``metric_seg.labels``.
    row, col : float
        The sketch point, in sketch pixels (finite numbers).
    target : {"interior", "mirror"}, keyword-only
        ``interior``: the interior point of the largest matched metric region (the place
        accuracy rule). ``mirror``: the point of the matched metric regions that best mirrors
        the tap's position in its sketch region (see the module docstring).
    tolerance : float, keyword-only
        Pixels from a region within which a tap on a wall still counts (10, as the annotators).
    yaw : float, keyword-only
        Heading of the goal pose in the map frame (radians).
    suggest_nearest : bool, keyword-only
        For an unmatched tap, find the nearest matched sketch region (one distance transform
        of the sketch); place accuracy passes False.

    Returns
    -------
    Goal
        ``goal.ok`` False with a ``reason`` when the tap is off every region or its region is
        unmatched.

    Raises
    ------
    ParameterError
        ``target`` unknown; ``row``, ``col``, ``tolerance`` or ``yaw`` not a finite number
        (``tolerance`` >= 0); a segmentation without a 2-D label image; ``metric_map`` of
        another shape than ``metric_seg`` (the arguments swapped?).
    SegmentationError, RegionsRecomputedWarning
        As :func:`match_table`, for a Correspondences.

    Examples
    --------
    >>> from ursim_core.segmentation.interface import Segmentation
    >>> from ursim_core.segmentation.graph import region_graph
    >>> labels = np.zeros((10, 20), np.int32); labels[:, :9] = 1; labels[:, 11:] = 2
    >>> seg = Segmentation(labels=labels, graph=region_graph(labels))
    >>> goal = locate([(1, 2), (2, 1)], seg, seg, None, 4, 3)
    >>> goal.sketch_region, goal.metric_region, goal.pixel
    (1, 2, (4, 15))
    >>> locate([(1, 2)], seg, seg, None, 4, 15).reason
    'sketch region 2 is not matched to any metric region'
    """
    if target not in TARGETS:
        raise ParameterError(f"target must be one of {', '.join(TARGETS)}, got {target!r}", field="target")
    _check_inputs(sketch_seg, metric_seg, metric_map, row, col, tolerance, yaw)
    # A correspondence file's stored ids may be another segmentation's: its points decide.
    table = match_table(match, sketch_seg, metric_seg, tolerance=tolerance)
    point = (int(round(float(row))), int(round(float(col))))
    sketch_region = regions_at_points(sketch_seg.labels, [point], tolerance=tolerance)[0]
    if sketch_region == 0:
        return Goal(
            sketch_point=point,
            sketch_region=0,
            reason=f"no sketch region within {tolerance:g} px of ({point[0]}, {point[1]})",
            nearest=_nearest_matched(table, sketch_seg.labels, point) if suggest_nearest else None,
        )
    metric_graph = metric_seg.graph
    metric_regions = tuple(r for r in table.metric_of.get(sketch_region, ()) if r in metric_graph)
    clique_id, label = table.clique_of.get(sketch_region), table.label_of.get(sketch_region)
    if not metric_regions:
        return Goal(
            sketch_point=point,
            sketch_region=sketch_region,
            clique_id=clique_id,
            label=label,
            reason=f"sketch region {sketch_region} is not matched to any metric region",
            nearest=_nearest_matched(table, sketch_seg.labels, point) if suggest_nearest else None,
        )
    if target == "interior":
        chosen, pixel = interior_target(metric_graph, metric_regions)
    else:
        pixel = _mirrored_pixel(table, sketch_seg, metric_seg, sketch_region, metric_regions, point)
        chosen = int(metric_seg.labels[pixel])
    pose = None
    if metric_map is not None and getattr(metric_map, "resolution", None) is not None:
        from ursim_core.io.maps import pixel_to_world

        x, y = pixel_to_world(metric_map, pixel[0], pixel[1])
        pose = (float(x), float(y), float(yaw))
    return Goal(
        sketch_point=point,
        sketch_region=sketch_region,
        metric_regions=metric_regions,
        metric_region=int(chosen),
        pixel=(int(pixel[0]), int(pixel[1])),
        pose=pose,
        clique_id=clique_id,
        label=label,
    )


def _check_inputs(sketch_seg, metric_seg, metric_map, row, col, tolerance, yaw) -> None:
    """Refuse what would give a wrong goal without a word (swapped maps) or a numpy error."""
    for name, value in (("row", row), ("col", col), ("yaw", yaw)):
        if not _is_finite(value):
            raise ParameterError(f"must be a finite number, got {value!r}", field=name)
    if not (_is_finite(tolerance) and tolerance >= 0):
        raise ParameterError(f"must be a finite number of pixels >= 0, got {tolerance!r}", field="tolerance")
    for name, seg in (("sketch_seg", sketch_seg), ("metric_seg", metric_seg)):
        if np.ndim(getattr(seg, "labels", None)) != 2:
            raise ParameterError(
                f"must be a Segmentation (a 2-D label image and its region graph), got {type(seg).__name__}",
                field=name,
            )
    if metric_map is not None:
        map_shape = tuple(np.shape(getattr(metric_map, "free", None)))
        seg_shape = tuple(np.shape(metric_seg.labels))
        if map_shape != seg_shape:
            raise ParameterError(
                f"metric_map is {_size(map_shape)} but metric_seg is {_size(seg_shape)}: "
                "not the segmentation of this map (sketch and metric arguments swapped?)",
                field="metric_map",
            )


def _is_finite(value: Any) -> bool:
    try:
        return math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def _size(shape: tuple) -> str:
    return "x".join(str(n) for n in shape) if shape else "not a map"


def _nearest_matched(table: MatchTable, labels: np.ndarray, point: tuple[int, int]) -> NearestMatch | None:
    from scipy import ndimage

    matched = np.isin(labels, np.fromiter(table.metric_of.keys(), dtype=np.int64, count=len(table.metric_of)))
    if not matched.any():
        return None
    rows, cols = labels.shape
    # Clamp a tap outside the image onto it; the distance is still measured from the tap.
    inside = (min(max(point[0], 0), rows - 1), min(max(point[1], 0), cols - 1))
    _, (near_rows, near_cols) = ndimage.distance_transform_edt(~matched, return_indices=True)
    found = (int(near_rows[inside]), int(near_cols[inside]))
    return NearestMatch(
        sketch_region=int(labels[found]),
        point=found,
        distance=math.hypot(found[0] - point[0], found[1] - point[1]),
    )


def _mirrored_pixel(table, sketch_seg, metric_seg, sketch_region, metric_regions, point) -> tuple[int, int]:
    sketch_nodes, metric_nodes = sketch_seg.graph.nodes, metric_seg.graph.nodes
    sketch_size = sketch_nodes[sketch_region]["size"]
    metric_sizes = np.array([metric_nodes[r]["size"] for r in metric_regions], dtype=float)
    metric_centroids = np.array([metric_nodes[r]["centroid"] for r in metric_regions], dtype=float)
    target_centroid = (metric_centroids * metric_sizes[:, None]).sum(axis=0) / metric_sizes.sum()
    linear = _centroid_alignment(table, sketch_seg.graph, metric_seg.graph)
    if linear is None:
        linear = math.sqrt(metric_sizes.sum() / sketch_size) * np.eye(2)
    offset = np.asarray(point, dtype=float) - np.asarray(sketch_nodes[sketch_region]["centroid"], dtype=float)
    wanted = target_centroid + linear @ offset
    # The nearest pixel of the matched regions (inside their bounding box) to the wanted point.
    boxes = np.array([metric_nodes[r]["bbox"] for r in metric_regions])
    top, left = boxes[:, 0].min(), boxes[:, 1].min()
    bottom, right = boxes[:, 2].max(), boxes[:, 3].max()
    window = np.isin(metric_seg.labels[top:bottom, left:right], metric_regions)
    rows, cols = np.nonzero(window)
    squared = (rows + top - wanted[0]) ** 2 + (cols + left - wanted[1]) ** 2
    best = int(np.argmin(squared))
    return (int(rows[best] + top), int(cols[best] + left))


def _centroid_alignment(table: MatchTable, sketch_graph, metric_graph) -> np.ndarray | None:
    """The 2x2 linear part (rotation or reflection, times scale) of the least-squares similarity
    from matched sketch centroids to metric centroids (Umeyama); None with fewer than 3 pairs or
    collinear centroids."""
    pairs = [(s, m) for s, m in table.pairs if s in sketch_graph and m in metric_graph]
    if len(pairs) < 3:
        return None
    source = np.array([sketch_graph.nodes[s]["centroid"] for s, _ in pairs], dtype=float)
    destination = np.array([metric_graph.nodes[m]["centroid"] for _, m in pairs], dtype=float)
    source_centred = source - source.mean(axis=0)
    destination_centred = destination - destination.mean(axis=0)
    variance = float((source_centred**2).sum())
    spread = np.linalg.svd(source_centred, compute_uv=False)
    # Collinear centroids fix the map along one axis only: the other could be turned either way.
    if variance == 0.0 or spread[-1] < 0.05 * spread[0]:
        return None
    u, singular, vt = np.linalg.svd(destination_centred.T @ source_centred)
    # Reflections are allowed: people draw mirrored sketches.
    rotation = u @ vt
    scale = float(singular.sum()) / variance
    return scale * rotation
