"""Orientation of a sketch relative to its metric map: candidates, and region graphs turned to them.

People draw sketches in any orientation, and sometimes mirrored. The signatures of
:mod:`~ursim_core.matching.descriptors` do not see orientation, but the position term does (it
compares region centroids normalised to each map's extent), and so does the planar matcher (the
cyclic order of neighbours reverses in a mirror image). So the matcher tries the orientations a
sketch can plausibly have and keeps the one whose best hypothesis scores lowest
(:func:`ursim_core.matching.pipeline.match`).

Which orientations: buildings are drawn with their walls along few directions. The dominant wall
direction of each map, modulo 90 degrees
(:func:`ursim_core.segmentation.canonical.wall_angle`), gives the turn that brings the
sketch's walls parallel to the metric map's; the four quarter turns of that, mirrored or not, are
the eight candidates (:func:`orientation_candidates`). A sketch turned by any angle, not only by
multiples of 90 degrees, is therefore handled.

A candidate is ``(degrees, mirrored)``: the sketch is mirrored left-right first (when ``mirrored``),
then turned ``degrees`` counter-clockwise as seen on the screen. :func:`oriented_graph` applies it
to the ``centroid`` and ``bbox`` attributes of a region graph; the label image is never touched, so
region ids and points stay in the sketch's own pixel frame. For a turn by a free angle, the boxes
come from the regions' outlines (:func:`region_outlines`): the box around a turned box is larger
than the region, and more so for a sketch drawn at an angle and turned back.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import networkx as nx
import numpy as np

from ursim_core.matching.config import ORIENTATIONS
from ursim_core.segmentation.canonical import wall_angle

__all__ = [
    "ORIENTATIONS",
    "SNAP_DEGREES",
    "wall_angle",
    "orientation_candidates",
    "oriented_graph",
    "region_outlines",
    "transform_points",
    "turn_between",
    "SAME_READING",
    "same_reading",
    "ranked_readings",
    "next_reading",
    "CLOSE_READING",
    "describe_gap",
    "broken_adjacencies",
    "misplaced_doors",
    "UNRELATED_DOOR",
    "DOOR_EVIDENCE",
]


def turn_between(first_degrees: float, second_degrees: float) -> float:
    """The smaller turn between two angles, in degrees (0 to 180).

    Examples
    --------
    >>> turn_between(359.5, 0.5), turn_between(90.0, 270.0), turn_between(10.0, -10.0)
    (1.0, 180.0, 20.0)
    """
    return abs((float(first_degrees) - float(second_degrees) + 180.0) % 360.0 - 180.0)


#: Orientations of one reading are a fraction of a degree apart (the answers of several
#: segmentations of one sketch read alike), those of two readings a quarter turn or a mirror image:
#: anything between separates them.
SAME_READING = 10.0


def same_reading(first: tuple[float, bool], second: tuple[float, bool]) -> bool:
    """Whether two ``(degrees, mirrored)`` orientations read a sketch alike: the same mirror image,
    turned less than :data:`SAME_READING` degrees apart.

    Examples
    --------
    >>> same_reading((359.6, True), (0.3, True)), same_reading((0.0, False), (0.0, True))
    (True, False)
    """
    return bool(first[1]) == bool(second[1]) and turn_between(first[0], second[0]) < SAME_READING


#: A runner-up reading ranked less than this much worse (relative, :func:`next_reading`) makes the
#: orientation a close call that a person should check. Round 37, the 18 KTH sketches turned by 15,
#: 30, ..., 345 degrees (432 sketch orientations; a study wrapper logging the gap of every answer of
#: ``ursim evaluate ... --augment angles=...``): with a gap of 5 % or more (357 of them) the sketch
#: was read as it is read upright every time (mean F1 0.79), with 2-5 % (37) in 81 % (0.66), with
#: 0.5-2 % (25) in 36 % (0.45) and under 0.5 % (13) in 23 % (0.41). Chosen on those sketches; it
#: only words the hint, the matcher never reads it.
CLOSE_READING = 0.02


def ranked_readings(orientation: tuple[float, bool], scan: dict) -> list[tuple[tuple[float, bool], float]]:
    """Every reading of ``scan``, ranked: ``orientation``'s own first, then the others from the best
    ranked, each with how much worse it ranked than the best of ``orientation``'s reading.

    ``scan`` is a result's ``orientation_scan`` (rank values, lower is better; for a vote over
    resamplings, the means over them). Orientations that read the sketch alike
    (:func:`same_reading`) are one reading, given by its best-ranked orientation. The gap is
    relative, ``(value - best) / best``: a few percent means the matcher could nearly as well have
    read the sketch that way, and a person should check the orientation. It is negative when a
    reading ranked better (a vote by count can choose so). Empty when ``scan`` holds none of this
    reading with a finite rank value (or its best is not above 0); values that are not finite (a
    reading no segmentation could rank) say nothing of the gap and are left out.

    Examples
    --------
    >>> scan = {(90.0, False): 0.50, (0.0, True): 0.51, (270.0, False): 0.8, (0.4, True): 0.6}
    >>> ranked_readings((90.2, False), scan)
    [((90.2, False), 0.0), ((0.0, True), 0.02), ((270.0, False), 0.6)]
    >>> ranked_readings((0.0, False), {(0.0, False): 0.5, (180.0, False): float("inf")})
    [((0.0, False), 0.0)]
    >>> ranked_readings((0.0, False), {(90.0, False): 0.5})
    []
    """
    scan = {tried: float(value) for tried, value in scan.items() if math.isfinite(value)}
    own = [value for tried, value in scan.items() if same_reading(tried, orientation)]
    if not own or min(own) <= 0:
        return []
    best = min(own)
    ranked = [((float(orientation[0]), bool(orientation[1])), 0.0)]
    # By value, ties by the orientation: the first of each reading is its best.
    for value, tried in sorted((value, tried) for tried, value in scan.items() if not same_reading(tried, orientation)):
        if not any(same_reading(tried, kept) for kept, _ in ranked):
            ranked.append(((float(tried[0]), bool(tried[1])), round((value - best) / best, 12)))
    return ranked


def next_reading(orientation: tuple[float, bool], scan: dict) -> tuple[tuple[float, bool], float] | None:
    """The runner-up: the best-ranked reading of ``scan`` other than ``orientation``'s, and how much
    worse it ranked than the best of ``orientation``'s reading (:func:`ranked_readings`' second);
    None when there is no other.

    Examples
    --------
    >>> next_reading((90.2, False), {(90.0, False): 0.50, (0.0, True): 0.51, (270.0, False): 0.8})
    ((0.0, True), 0.02)
    >>> next_reading((0.0, False), {(0.0, False): 0.5}) is None
    True
    >>> next_reading((0.0, False), {(0.0, False): 0.5, (180.0, False): float("inf")}) is None
    True
    """
    ranked = ranked_readings(orientation, scan)
    return ranked[1] if len(ranked) > 1 else None


def broken_adjacencies(pairs, sketch_graph: nx.Graph, metric_graph: nx.Graph) -> float:
    """The share of an answer's sketch adjacencies that it breaks: of the edges of ``sketch_graph``
    whose two regions are both paired, those whose regions have no partners that are one and the
    same metric region or adjacent in ``metric_graph``. 0 when no such edge exists.

    A reading of a sketch of rooms along a corridor turned by a half turn, or mirrored, lays the
    room sizes of one row on the other. Its rooms can fit as well as the right reading's, but the
    doors between neighbouring rooms then join rooms that are not neighbours on the map
    (``MatchConfig.adjacency_penalty``, docs/studies.md, round 44).

    Examples
    --------
    >>> sketch = nx.Graph([(1, 2), (2, 3)]); metric = nx.Graph([(7, 8), (8, 9)])
    >>> broken_adjacencies([(1, 7), (2, 8), (3, 9)], sketch, metric)
    0.0
    >>> broken_adjacencies([(1, 7), (2, 9), (3, 8)], sketch, metric)
    0.5
    >>> broken_adjacencies([(1, 7), (2, 7), (3, 8)], sketch, metric), broken_adjacencies([], sketch, metric)
    (0.0, 0.0)
    """
    partners: dict = {}
    for sketch_region, metric_region in pairs:
        partners.setdefault(sketch_region, set()).add(metric_region)
    edges = [(u, v) for u, v in sketch_graph.edges() if u != v and u in partners and v in partners]
    if not edges:
        return 0.0
    kept = sum(any(a == b or metric_graph.has_edge(a, b) for a in partners[u] for b in partners[v]) for u, v in edges)
    return 1.0 - kept / len(edges)


def _door_offsets(graph: nx.Graph) -> dict:
    """Where each region touches each neighbour, from its centroid, in halves of its box's height
    and width: ``{(region, neighbour): (rows, cols)}``, both ways round, for the edges with a
    ``contact`` and the regions with a ``bbox``."""
    offsets = {}
    for a, b, contact in graph.edges(data="contact"):
        if contact is None:
            continue
        for region, neighbour in ((a, b), (b, a)):
            node = graph.nodes[region]
            box = node.get("bbox")
            if box is None:
                continue
            half_rows, half_cols = max(0.5, (box[2] - box[0]) / 2.0), max(0.5, (box[3] - box[1]) / 2.0)
            centre = node["centroid"]
            offsets[region, neighbour] = ((contact[0] - centre[0]) / half_rows, (contact[1] - centre[1]) / half_cols)
    return offsets


#: What :func:`misplaced_doors` counts for a contact of the sketch that the answer does not carry to
#: the map: about the distance between two doors placed at random on a wall (the offsets run from
#: -1 to 1 along it), not fitted.
UNRELATED_DOOR = 1.0


#: A reading whose :func:`misplaced_doors` is below this puts the sketch's doors about where the map
#: has them; when no reading does, the doors do not rank the readings (``MatchConfig.door_penalty``).
DOOR_EVIDENCE = 0.5


def misplaced_doors(pairs, sketch_graph: nx.Graph, metric_graph: nx.Graph) -> float:
    """How far an answer's regions touch their neighbours from where their partners touch theirs.

    For each region of ``sketch_graph`` and each neighbour: the place where the two touch (the
    edge's ``contact``, a door for two rooms split at it), from the region's centroid in halves of
    its box's height and width, against the same for their partners when the answer pairs both
    and the partners are neighbours in ``metric_graph`` (the closest partners, for a region paired
    more than once), else :data:`UNRELATED_DOOR`; the mean over them. 0 when the sketch graph has
    no contacts.

    The graphs must be in one frame (the sketch's turned to the reading, :func:`oriented_graph`).
    A half turn or mirror image of a sketch of rooms along a corridor can fit the rooms' sizes
    and neighbours as well as the right reading, but puts each room's door at the other end of
    its wall (``MatchConfig.door_penalty``, docs/studies.md, round 46).

    Examples
    --------
    >>> sketch = nx.Graph(); metric = nx.Graph()
    >>> for graph in (sketch, metric):
    ...     graph.add_node(1, centroid=(5.0, 5.0), bbox=(0, 0, 10, 10))
    ...     graph.add_node(2, centroid=(15.0, 5.0), bbox=(10, 0, 20, 10))
    >>> sketch.add_edge(1, 2, contact=(10.0, 2.0)); metric.add_edge(1, 2, contact=(10.0, 2.0))
    >>> misplaced_doors([(1, 1), (2, 2)], sketch, metric)
    0.0
    >>> metric.edges[1, 2]["contact"] = (10.0, 8.0)  # the door at the other end of the wall
    >>> round(misplaced_doors([(1, 1), (2, 2)], sketch, metric), 6)
    1.2
    """
    partners: dict = {}
    for sketch_region, metric_region in pairs:
        partners.setdefault(sketch_region, []).append(metric_region)
    sketch_offsets = _door_offsets(sketch_graph)
    if not sketch_offsets:
        return 0.0
    metric_offsets = _door_offsets(metric_graph)
    distances = []
    for (region, neighbour), offset in sketch_offsets.items():
        found = [
            math.dist(offset, metric_offsets[a, b])
            for a in partners.get(region, ())
            for b in partners.get(neighbour, ())
            if (a, b) in metric_offsets
        ]
        # A contact the answer does not carry to the map counts as an unrelated door: otherwise
        # an answer that pairs fewer regions would be judged on fewer doors, and fare better.
        distances.append(min(found) if found else UNRELATED_DOOR)
    return float(np.mean(distances))


def describe_gap(gap: float, *, hint: bool = True) -> str:
    """How much worse a reading ranked than the one taken (:func:`ranked_readings`), in words, with
    the hint to check the orientation when the call was close (:data:`CLOSE_READING`; not with
    ``hint=False``); what ``ursim match`` prints and the app shows.

    Examples
    --------
    >>> describe_gap(0.25), describe_gap(0.004)
    ('ranked 25.0% worse', 'ranked 0.4% worse: a close call, check the orientation')
    >>> describe_gap(-0.01, hint=False)
    'ranked 1.0% better'
    """
    text = f"ranked {abs(gap):.1%} {'worse' if gap >= 0 else 'better'}"
    return text + (": a close call, check the orientation" if hint and gap < CLOSE_READING else "")


#: Wall-angle differences below this many degrees are taken as none: the candidates are then the
#: exact quarter turns. The wall angle of a map turned by a quarter turn can come out a degree or
#: two apart (its outline is traced and simplified from another starting pixel), which turned
#: near-ties between candidates into different answers for the same sketch drawn in different
#: orientations; walls this close to the axes are how people draw, and the free-space fit
#: (:mod:`ursim_core.matching.alignment`) turns by a few degrees itself. The same threshold as
#: the canonical segmentation's (``ursim_core.segmentation.canonical``): below it, no resampling.
SNAP_DEGREES = 3.0


def orientation_candidates(
    *,
    orientation="any",
    mirrored: bool | None = None,
    sketch_angle: float = 0.0,
    metric_angle: float = 0.0,
) -> list[tuple[float, bool]]:
    """The ``(degrees, mirrored)`` turns to try for a sketch, the identity first.

    Parameters
    ----------
    orientation : 'any', 'upright' or float, keyword-only
        'upright': the sketch is drawn in the metric map's orientation (one candidate);
        a number: the sketch is brought to the metric map by turning it that many degrees
        counter-clockwise (after mirroring when ``mirrored``); 'any': unknown.
    mirrored : bool or None, keyword-only
        Whether the sketch is a mirror image; None = unknown (both are tried; 'upright' and a
        number of degrees then mean not mirrored).
    sketch_angle, metric_angle : float, keyword-only
        :func:`wall_angle` of each map, used by 'any'.

    Examples
    --------
    >>> orientation_candidates(orientation="upright")
    [(0.0, False)]
    >>> orientation_candidates(orientation=90, mirrored=True)
    [(90.0, True)]
    >>> orientation_candidates(mirrored=False, sketch_angle=10.0)
    [(350.0, False), (80.0, False), (170.0, False), (260.0, False)]
    >>> orientation_candidates(mirrored=False, sketch_angle=1.5)  # within SNAP_DEGREES
    [(0.0, False), (90.0, False), (180.0, False), (270.0, False)]
    """
    if orientation == "upright":
        return [(0.0, bool(mirrored))]
    if orientation != "any":
        return [(float(orientation) % 360.0, bool(mirrored))]
    flags = (False, True) if mirrored is None else (bool(mirrored),)
    candidates = []
    for flag in flags:
        # Mirroring negates every angle of the sketch, its walls' direction included.
        base = metric_angle - (-sketch_angle if flag else sketch_angle)
        base = (base + 45.0) % 90.0 - 45.0
        if abs(base) < SNAP_DEGREES:
            base = 0.0
        for quarter in range(4):
            candidates.append((round((base + 90.0 * quarter) % 360.0, 9) % 360.0, flag))
    return candidates


def transform_points(points: np.ndarray, *, degrees: float, mirrored: bool) -> np.ndarray:
    """(row, col) points mirrored left-right (when asked) then turned counter-clockwise about 0.

    Examples
    --------
    >>> transform_points(np.array([[0.0, 10.0]]), degrees=90, mirrored=False).round(6).tolist()
    [[-10.0, 0.0]]
    """
    points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    x, y_up = points[:, 1].copy(), -points[:, 0]
    if mirrored:
        x = -x
    theta = math.radians(degrees)
    c, s = math.cos(theta), math.sin(theta)
    x, y_up = c * x - s * y_up, s * x + c * y_up
    return np.stack([-y_up, x], axis=1)


def region_outlines(graph: nx.Graph, labels: np.ndarray) -> dict:
    """The corners of each region's convex hull, as (row, col) points of the pixel grid.

    A pixel (r, c) is the square from (r, c) to (r + 1, c + 1), as ``bbox`` counts it (max
    exclusive); the outline holds the corners of the hull's pixels, found in each region's
    ``bbox`` of the label image (regions without one are left out). Turned by any angle, the box
    around a region's turned outline is its tight bounding box in the turned frame
    (:func:`oriented_graph`).

    Examples
    --------
    >>> labels = np.zeros((4, 5), np.int32); labels[1:3, 1:4] = 1
    >>> from ursim_core.segmentation import region_graph
    >>> outline = region_outlines(region_graph(labels), labels)[1]
    >>> outline.min(axis=0).tolist(), outline.max(axis=0).tolist()
    ([1.0, 1.0], [3.0, 4.0])
    """
    import cv2

    labels = np.asarray(labels)
    outlines = {}
    for region, box in graph.nodes(data="bbox"):
        if box is None:
            continue
        rows, cols = slice(int(box[0]), int(box[2])), slice(int(box[1]), int(box[3]))
        mask = (labels[rows, cols] == region).astype(np.uint8)
        contours, _ = cv2.findContours(mask, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
        if not contours:
            continue
        points = np.concatenate([contour.reshape(-1, 2) for contour in contours])
        hull = cv2.convexHull(points).reshape(-1, 2)
        # (x, y) pixel indices of the crop to (row, col) corners of those pixels in the map.
        corner_rows = hull[:, 1][:, None] + rows.start + np.array([0, 0, 1, 1])
        corner_cols = hull[:, 0][:, None] + cols.start + np.array([0, 1, 0, 1])
        outlines[region] = np.stack([corner_rows.ravel(), corner_cols.ravel()], axis=1).astype(np.float64)
    return outlines


def oriented_graph(graph: nx.Graph, *, degrees: float, mirrored: bool, outlines: dict | None = None) -> nx.Graph:
    """A copy of a region graph whose ``centroid``, ``bbox`` and edges' ``contact`` are turned to a candidate.

    The bounding box of a turned region is the box around its turned corners. Other attributes
    (size, shape, interior point) are kept as they are; the identity returns the graph itself.
    ``outlines`` (:func:`region_outlines`, by region): for a turn that is not a quarter turn, the
    box is the one around the region's turned outline instead. The box around a turned box grows
    (by up to 41 % per side at 45 degrees, twice for a sketch drawn at that angle and turned
    back), and the regions' positions are normalised to the union of the boxes
    (:mod:`ursim_core.matching.positions`); a quarter turn keeps boxes exact either way.

    Examples
    --------
    >>> g = nx.Graph(); g.add_node(1, centroid=(0.0, 10.0), bbox=(0, 0, 2, 20))
    >>> (np.round(oriented_graph(g, degrees=180, mirrored=False).nodes[1]["centroid"], 6) + 0.0).tolist()
    [0.0, -10.0]
    """
    if not mirrored and degrees % 360.0 == 0.0:
        return graph
    out = graph.copy()
    nodes: Sequence = list(out.nodes)
    if not nodes:
        return out
    centroids = np.array([out.nodes[n]["centroid"] for n in nodes], dtype=np.float64).reshape(-1, 2)
    moved = transform_points(centroids, degrees=degrees, mirrored=mirrored)
    with_box = [n for n in nodes if "bbox" in out.nodes[n]]
    if with_box:
        boxes = np.array([out.nodes[n]["bbox"] for n in with_box], dtype=np.float64).reshape(-1, 4)
        corners = np.stack([boxes[:, [0, 1]], boxes[:, [0, 3]], boxes[:, [2, 1]], boxes[:, [2, 3]]], axis=1).reshape(
            -1, 2
        )
        turned = transform_points(corners, degrees=degrees, mirrored=mirrored).reshape(-1, 4, 2)
        low, high = turned.min(axis=1), turned.max(axis=1)
        if outlines and degrees % 90.0 != 0.0:
            outlined = [i for i, node in enumerate(with_box) if node in outlines and len(outlines[node])]
            if outlined:
                # All outlines turned by one call, each one's box by a segmented reduction: the
                # same values as turning them one by one (elementwise arithmetic), at a tenth of
                # the calls (a turned sketch's regions are turned about twenty times a match).
                points = [outlines[with_box[i]] for i in outlined]
                starts = np.cumsum([0] + [len(outline) for outline in points[:-1]])
                turned_points = transform_points(np.concatenate(points), degrees=degrees, mirrored=mirrored)
                low[outlined] = np.minimum.reduceat(turned_points, starts, axis=0)
                high[outlined] = np.maximum.reduceat(turned_points, starts, axis=0)
        for i, node in enumerate(with_box):
            out.nodes[node]["bbox"] = (float(low[i, 0]), float(low[i, 1]), float(high[i, 0]), float(high[i, 1]))
    for i, node in enumerate(nodes):
        out.nodes[node]["centroid"] = (float(moved[i, 0]), float(moved[i, 1]))
    touching = [(a, b) for a, b, contact in out.edges(data="contact") if contact is not None]
    if touching:
        contacts = np.array([out.edges[edge]["contact"] for edge in touching], dtype=np.float64).reshape(-1, 2)
        for edge, point in zip(touching, transform_points(contacts, degrees=degrees, mirrored=mirrored)):
            out.edges[edge]["contact"] = (float(point[0]), float(point[1]))
    return out
