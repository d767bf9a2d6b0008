"""One sketch orientation prepared for matching: the candidates, and each one's ``Prepared``.

:func:`ursim_core.matching.prepare` tries the orientations a sketch can have
(:func:`orientations_to_try`); each is prepared by :func:`prepare_oriented` for the first and
:func:`reoriented` for the others, which reuse the first's signatures (only the position term and
the neighbour orders depend on the orientation), and ranked with the free-space overlap of the
sketch fitted onto the metric map in it (:func:`candidate_overlaps`); a partial sketch's reading
may be taken from where it resembles part of the map (:func:`window_reading`).
"""

from __future__ import annotations

import dataclasses

import networkx as nx
import numpy as np

from ursim_core.matching.config import MatchConfig
from ursim_core.matching.descriptors import pair_descriptors
from ursim_core.matching.orientation import orientation_candidates, oriented_graph, region_outlines, turn_between
from ursim_core.matching.planar import planar_graph
from ursim_core.matching.positions import blend_position_arrays, metric_positions_of, region_positions
from ursim_core.matching.results import Prepared
from ursim_core.segmentation.canonical import wall_angle
from ursim_core.segmentation.interface import Segmentation

__all__ = [
    "region_graph_of",
    "orientations_to_try",
    "nearest_orientations",
    "sketch_outlines",
    "prepare_oriented",
    "reoriented",
    "candidate_overlaps",
    "carried_by_orientation",
    "finalist_windows",
    "turned_windows",
    "window_position_starts",
    "window_reading",
]


def region_graph_of(segmentation_or_graph) -> nx.Graph:
    """The region graph of a :class:`~ursim_core.segmentation.Segmentation`, or the graph given."""
    if isinstance(segmentation_or_graph, nx.Graph):
        return segmentation_or_graph
    return segmentation_or_graph.graph


def orientations_to_try(config: MatchConfig, sketch_seg, metric_seg) -> list[tuple[float, bool]]:
    """The ``(degrees, mirrored)`` orientations worth trying: only those that can change the answer.

    ``config.orientation`` other than ``'any'`` names the one; without the position term only a
    mirror image changes the planar matcher's answer (both readings, unless ``config.mirrored``
    says which) and nothing changes the other graph matchers'; otherwise the
    candidates of :func:`~ursim_core.matching.orientation.orientation_candidates` from both maps'
    wall angles (read from their label images; 0 for bare graphs).

    Examples
    --------
    >>> orientations_to_try(MatchConfig(orientation="upright", mirrored=False), None, None)
    [(0.0, False)]
    >>> len(orientations_to_try(MatchConfig(), nx.Graph(), nx.Graph()))  # 4 turns, mirrored or not
    8
    """
    if config.orientation != "any":
        return orientation_candidates(orientation=config.orientation, mirrored=config.mirrored)
    if config.position_weight == 0 and config.matcher != "overlay":
        # Without the position term only a mirror image changes anything (the planar
        # matcher's neighbour orders reverse); the other graph matchers do not see orientation.
        if config.matcher != "planar" or config.mirrored is not None:
            return [(0.0, bool(config.mirrored))]
        return [(0.0, False), (0.0, True)]
    return orientation_candidates(
        orientation="any",
        mirrored=config.mirrored,
        sketch_angle=_wall_angle_of(sketch_seg),
        metric_angle=_wall_angle_of(metric_seg),
    )


def _wall_angle_of(segmentation) -> float:
    """The wall angle of a segmentation's label image (a :class:`Segmentation` keeps it), 0 for a
    bare graph."""
    if isinstance(segmentation, Segmentation):
        return segmentation.wall_angle
    labels = getattr(segmentation, "labels", None)
    return wall_angle(labels) if labels is not None else 0.0


def nearest_orientations(candidates, wanted) -> list[tuple[float, bool]]:
    """For each ``(degrees, mirrored)`` of ``wanted``, the candidate of the same mirror flag whose
    turn is closest to it; each once, in the order of ``wanted``; all ``candidates`` if none fits.

    Another segmentation of the same sketch in the same frame has wall angles a fraction of a
    degree apart, so its candidates are the first segmentation's turned by that fraction: this
    finds the ones that read the sketch the same way.

    Examples
    --------
    >>> candidates = [(1.0, False), (91.0, False), (181.0, False), (271.0, False), (359.0, True)]
    >>> nearest_orientations(candidates, [(180.0, False), (0.0, True), (178.0, False)])
    [(181.0, False), (359.0, True)]
    """
    chosen = []
    for orientation in wanted:
        nearest = _nearest_of_same_flag(candidates, orientation)
        if nearest is not None and nearest not in chosen:
            chosen.append(nearest)
    return chosen or list(candidates)


def _nearest_of_same_flag(orientations, orientation) -> tuple[float, bool] | None:
    """The one of ``orientations`` with the mirror flag of ``orientation`` whose turn is closest
    to it (the first of equals); None when none has that flag."""
    degrees, mirrored = orientation
    same_flag = [other for other in orientations if bool(other[1]) == bool(mirrored)]
    if not same_flag:
        return None
    return min(same_flag, key=lambda other: turn_between(other[0], degrees))


def sketch_outlines(sketch_seg, sketch_graph: nx.Graph, candidates) -> dict | None:
    """The sketch's region outlines (:func:`~ursim_core.matching.orientation.region_outlines`)
    when a candidate is not a quarter turn and the label image is at hand; else None."""
    labels = getattr(sketch_seg, "labels", None)
    if labels is None or all(degrees % 90.0 == 0.0 for degrees, _ in candidates):
        return None
    return region_outlines(sketch_graph, labels)


def reoriented(
    base: Prepared, sketch_graph: nx.Graph, orientation: tuple[float, bool], outlines: dict | None = None
) -> Prepared:
    """``base`` for another orientation of the sketch: new positions, same signatures."""
    turned = oriented_graph(sketch_graph, degrees=orientation[0], mirrored=orientation[1], outlines=outlines)
    descriptors = base.descriptors
    if descriptors is not None and descriptors.signature_c is not None:
        c_matrix = blend_position_arrays(
            descriptors.signature_c,
            region_positions(turned, nodes=descriptors.sketch_nodes),
            metric_positions_of(descriptors, base.metric_graph),
            base.config.position_weight,
        )
        descriptors = dataclasses.replace(descriptors, c_matrix=c_matrix)
    return dataclasses.replace(
        base, sketch_graph=turned, descriptors=descriptors, sketch_planar=planar_graph(turned), orientation=orientation
    )


def prepare_oriented(
    sketch_graph, metric_graph, config: MatchConfig, orientation: tuple[float, bool], outlines: dict | None = None
) -> Prepared:
    """Everything the matchers need of the pair with the sketch in ``orientation``, but no answer.

    The descriptors (:func:`~ursim_core.matching.descriptors.pair_descriptors`: attributes,
    anchors, signatures, ``c``) and both planar graphs; ``notes`` say what is degenerate (no
    region, one region, several components, no unique region), for the answer's ``reason``.

    Examples
    --------
    >>> g = nx.path_graph(3)
    >>> nx.set_node_attributes(g, {0: 50, 1: 10, 2: 12}, "size")
    >>> nx.set_node_attributes(g, 0.3, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    >>> prepared = prepare_oriented(g, g.copy(), MatchConfig(), (180.0, False))
    >>> prepared.c_matrix.shape, prepared.orientation
    ((3, 3), (180.0, False))
    """
    sketch_graph = oriented_graph(sketch_graph, degrees=orientation[0], mirrored=orientation[1], outlines=outlines)
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


def candidate_overlaps(config: MatchConfig, sketch_seg, metric_seg, candidates, indices) -> dict[int, float]:
    """Free-space overlap of the sketch fitted onto the metric map, per candidate orientation
    (empty when not asked for or when either side is a bare graph with no label image)."""
    sketch_labels = getattr(sketch_seg, "labels", None)
    metric_labels = getattr(metric_seg, "labels", None)
    if config.orientation_overlap == 0 or sketch_labels is None or metric_labels is None:
        return {}
    from ursim_core.matching.alignment import fit_alignments

    fitted = fit_alignments(sketch_labels, metric_labels, [candidates[index] for index in indices])
    return {index: max(alignment.overlap, _SMALLEST_OVERLAP) for index, alignment in zip(indices, fitted)}


def carried_by_orientation(measured: dict, candidates, indices) -> dict | None:
    """Values of ``candidates`` (at ``indices``) taken from those ``measured`` on another
    segmentation of the same sketch, ``{(degrees, mirrored): value}``: each from the measured
    orientation of the same mirror flag nearest in turn. None when a candidate has no such one.

    The values are the free-space overlaps (:func:`candidate_overlaps`) and the best windows
    (:func:`finalist_windows`). The segmentations of one sketch share its frame, and their
    candidate orientations are a fraction of a degree apart, as are their free spaces: fitting each
    again (about 7 ms per segmentation of a KTH sketch) finds the same overlaps up to resampling
    noise.

    Examples
    --------
    >>> measured = {(0.4, False): 0.8, (90.4, False): 0.5, (0.4, True): 0.6}
    >>> carried_by_orientation(measured, [(90.1, False), (0.1, True)], [0, 1])
    {0: 0.5, 1: 0.6}
    >>> carried_by_orientation(measured, [(180.0, True), (270.0, True)], [1])
    {1: 0.6}
    >>> carried_by_orientation({(0.0, False): 0.8}, [(0.0, True)], [0]) is None
    True
    """
    carried = {}
    for index in indices:
        nearest = _nearest_of_same_flag(measured, candidates[index])
        if nearest is None:
            return None
        carried[index] = measured[nearest]
    return carried


#: Floor of an overlap used as a divisor (a sketch with no free space, say).
_SMALLEST_OVERLAP = 1e-3


def finalist_windows(sketch_labels, metric_labels, orientations, *, searched=None) -> dict:
    """For each ``(degrees, mirrored)`` orientation, ``(correlation, gain)`` of the best window of
    the metric map for the sketch turned so (:func:`~ursim_core.matching.template.best_window`),
    or None when there is none (an empty map). ``searched``: :func:`turned_windows` already found.

    Examples
    --------
    >>> import numpy as np
    >>> plan = np.zeros((300, 600), np.int32)
    >>> plan[20:130, 20:150], plan[20:130, 160:400], plan[20:130, 410:580] = 1, 2, 3
    >>> plan[140:170, 20:580], plan[180:280, 20:260], plan[180:280, 270:580] = 4, 5, 6
    >>> found = finalist_windows(plan[:, :320], plan, [(0.0, False), (180.0, False)])
    >>> found[(0.0, False)][0] > found[(180.0, False)][0]
    True
    """
    searched = turned_windows(sketch_labels, metric_labels, orientations, searched=searched)
    return {
        orientation: None if window is None else (window.correlation, window.gain)
        for orientation, (_, window) in searched.items()
    }


def turned_windows(sketch_labels, metric_labels, orientations, *, searched=None) -> dict:
    """``{(degrees, mirrored): (turned free space, window)}``: the sketch's free space turned so
    (:func:`~ursim_core.matching.layings.oriented_labels` of its mask: the turned labels' mask) and
    its best window on the metric map (:func:`~ursim_core.matching.template.best_window`, None when
    there is none); those already in ``searched`` are taken from it. The reading's windows
    (``window_reading_margin``) and the refit's starts (``window_start``) are found once for both.

    Examples
    --------
    >>> plan = np.zeros((300, 600), np.int32)
    >>> plan[20:130, 20:150], plan[20:130, 160:400], plan[20:130, 410:580] = 1, 2, 3
    >>> plan[140:170, 20:580], plan[180:280, 20:260], plan[180:280, 270:580] = 4, 5, 6
    >>> found = turned_windows(plan[:, :320], plan, [(90.0, False)])
    >>> turned, window = found[(90.0, False)]
    >>> turned.shape, turned.dtype, turned_windows(None, None, [(90.0, False)], searched=found) == found
    ((320, 300), dtype('bool'), True)
    """
    from ursim_core.matching import template
    from ursim_core.matching.layings import oriented_labels

    searched = searched or {}
    found = {}
    metric_free = sketch_free = None
    for degrees, mirrored in orientations:
        if (degrees, mirrored) in searched:
            found[(degrees, mirrored)] = searched[(degrees, mirrored)]
            continue
        if metric_free is None:
            metric_free, sketch_free = np.asarray(metric_labels) > 0, np.asarray(sketch_labels) > 0
        # The window reads only the free space: its mask is turned, not the ids (half the time).
        turned = oriented_labels(sketch_free, degrees=degrees, mirrored=mirrored)
        found[(degrees, mirrored)] = (turned, template.best_window(turned, metric_free))
    return found


def window_position_starts(sketch_labels, metric_labels, preparations: dict, *, searched=None) -> dict:
    """For each ``(degrees, mirrored): Prepared`` of ``preparations``, the scale and shift per axis
    (a :func:`~ursim_core.matching.refit.fit_axis_transform` array) that carry its sketch graph's
    centroids into the window of the metric map where the sketch, turned so, correlates best
    (:func:`~ursim_core.matching.template.best_window`); None when that window correlates less than
    ``WINDOW_GAIN`` better than the map's whole box or under ``WINDOW_MIN_CORRELATION`` (the window
    laying's thresholds), or fewer than three regions are found in both frames. ``searched``: :func:`turned_windows` already found.

    Positions normalised by each map's extent assume the sketch shows the whole map; a sketch
    of part of it, laid in the part it resembles, starts the refit where its regions are
    (``MatchConfig.window_start``). The graph's centroids and the turned label image's differ by
    a shift per axis (the turn's canvas): the transform is fitted from one to the other, then
    composed with the window's laying.

    Examples
    --------
    >>> import networkx as nx
    >>> plan = np.zeros((300, 600), np.int32)
    >>> plan[20:130, 20:150], plan[20:130, 160:400], plan[20:130, 410:580] = 1, 2, 3
    >>> plan[140:170, 20:580], plan[180:280, 20:260], plan[180:280, 270:580] = 4, 5, 6
    >>> sketch = plan[:, :320]
    >>> graph = nx.Graph()
    >>> graph.add_nodes_from((r, {"centroid": tuple(np.argwhere(sketch == r).mean(axis=0))}) for r in (1, 2, 4, 5, 6))
    >>> class Oriented: sketch_graph = graph
    >>> transform = window_position_starts(sketch, plan, {(0.0, False): Oriented()})[(0.0, False)]
    >>> np.round(transform[:, 0], 1).tolist()   # the left half laid on the plan's left half: scale 1
    [1.0, 1.0]
    """
    from ursim_core.matching import template
    from ursim_core.matching.layings import oriented_labels, region_centroids

    starts = {}
    for orientation, (turned, window) in turned_windows(
        sketch_labels, metric_labels, preparations, searched=searched
    ).items():
        prepared = preparations[orientation]
        starts[orientation] = None
        if window is None or window.gain < template.WINDOW_GAIN or window.correlation < template.WINDOW_MIN_CORRELATION:
            continue
        row0, row1, col0, col1 = template.free_box(turned)
        scale = np.array([window.height / (row1 - row0), window.width / (col1 - col0)])
        shift = np.array([window.top, window.left]) - scale * np.array([row0, col0])
        # The ids are turned only for a window that starts the refit.
        centroids = region_centroids(
            oriented_labels(np.asarray(sketch_labels), degrees=orientation[0], mirrored=orientation[1])
        )
        nodes = [node for node in prepared.sketch_graph.nodes if node in centroids]
        if len(nodes) < 3:
            continue
        graph_points = np.array([prepared.sketch_graph.nodes[node]["centroid"] for node in nodes], dtype=np.float64)
        laid = scale * np.array([centroids[node] for node in nodes], dtype=np.float64) + shift
        transform = np.zeros((2, 2))
        for axis in range(2):
            design = np.stack([graph_points[:, axis], np.ones(len(nodes))], axis=1)
            transform[axis] = np.linalg.lstsq(design, laid[:, axis], rcond=None)[0]
        starts[orientation] = transform
    return starts


def window_reading(windows: dict, ranked_best, *, margin: float):
    """The key of ``windows`` (by finalist: ``(correlation, gain)`` or None) whose sketch, read so,
    resembles a part of the metric map clearly better than it does read as ``ranked_best`` (the
    reading the matcher ranks best): its window correlates at least
    :data:`~ursim_core.matching.template.WINDOW_GAIN` better than the map's whole box (the sketch
    looks partial read so), at least :data:`~ursim_core.matching.template.WINDOW_MIN_CORRELATION`
    in all, and at least ``margin`` better than ``ranked_best``'s; the best correlating of those, or
    None.

    Examples
    --------
    >>> windows = {0: (0.62, 0.02), 1: (0.89, 0.30), 2: (0.70, 0.20)}
    >>> window_reading(windows, 0, margin=0.1), window_reading(windows, 1, margin=0.1)
    (1, None)
    >>> window_reading({0: (0.62, 0.02), 1: (0.68, 0.30)}, 0, margin=0.1) is None
    True
    """
    from ursim_core.matching import template

    if windows.get(ranked_best) is None:
        return None
    floor = max(template.WINDOW_MIN_CORRELATION, windows[ranked_best][0] + margin)
    partial = [
        (found[0], key)
        for key, found in windows.items()
        if found is not None and found[1] >= template.WINDOW_GAIN and found[0] >= floor
    ]
    return max(partial, key=lambda item: item[0])[1] if partial else None
