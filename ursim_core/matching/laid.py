"""The elastic answer in the matching pipeline (``MatchConfig.elastic``).

The planar matcher reads the sketch's orientation and votes over its segmentations; the answer's
pairs are then those of the sketch laid and bent onto the metric map in that orientation
(:mod:`ursim_core.matching.elastic`), laid box onto box or, with ``MatchConfig.elastic_laying``,
also by the planar answer's own pairs, whichever lands more on the metric map's free space once
bent; completed by the planar answer's pairs of regions left unpaired on both sides ('completed'),
within a person's constraints. :func:`prepare <ursim_core.matching.prepare>` starts the first
segmentation's laying on a thread (:class:`LaidAhead`) while the other segmentations are prepared.
"""

from __future__ import annotations

from ursim_core.matching.config import ELASTIC_LAYING_RULES
from ursim_core.matching.results import MatchResult, Prepared, replaced

__all__ = [
    "sketch_sized_labels",
    "elastic_labels",
    "LaidAhead",
    "laying_answer",
    "window_rule",
    "laid_by_answer",
    "laid_in",
    "joined_partners",
    "laid_elastically",
]


def sketch_sized_labels(prepared: Prepared, sketch_seg, metric_seg, *, largest: int) -> tuple | None:
    """The two label images of segmentations (not bare graphs) of at most ``largest`` regions a map
    (``prepared``'s c matrix), which are laid on each other; else None."""
    sketch_labels, metric_labels = getattr(sketch_seg, "labels", None), getattr(metric_seg, "labels", None)
    # Sketch-sized maps only: at the working size (512 px) a building's thousands of regions
    # would be a few pixels wide, and its graph answer is not screened by orientation alike.
    if sketch_labels is None or metric_labels is None or max(prepared.c_matrix.shape) > largest:
        return None
    return sketch_labels, metric_labels


def elastic_labels(prepared: Prepared, sketch_seg, metric_seg, *, largest: int) -> tuple | None:
    """The two label images when the answer's pairs are to be the laid sketch's (``MatchConfig.elastic``):
    the planar matcher and :func:`sketch_sized_labels`."""
    if prepared.config.elastic == "off" or prepared.config.matcher != "planar":
        return None
    return sketch_sized_labels(prepared, sketch_seg, metric_seg, largest=largest)


class LaidAhead:
    """:func:`~ursim_core.matching.elastic.lay_sketch` of one orientation (given the answer to fit
    a laying to, as :func:`laying_answer` gives it), run on a thread from the start; :meth:`laid`
    waits for it. The same result as a call made later (no shared state but the metric map's
    memos of its working image and centroids)."""

    def __init__(
        self, sketch_labels, metric_labels, orientation, min_iou: float, answer=None, *, window: str = "off"
    ) -> None:
        import threading

        self._laid = None
        self._error: BaseException | None = None
        arguments = (sketch_labels, metric_labels, orientation, min_iou, answer, window)
        self._thread = threading.Thread(target=self._run, args=arguments, daemon=True)
        self._thread.start()

    def _run(self, sketch_labels, metric_labels, orientation, min_iou, answer, window) -> None:
        try:
            self._laid = _lay(sketch_labels, metric_labels, orientation, min_iou, answer, window=window)
        except BaseException as error:  # re-raised where the result is read
            self._error = error

    def laid(self):
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._laid


def laying_answer(prepared: Prepared, orientation: tuple, result: MatchResult | None = None):
    """The pairs the sketch is also laid by in ``orientation`` (``MatchConfig.elastic_laying``):
    the answer found while the orientation was chosen (``Prepared.chosen``, at the automatic m)
    when it reads the sketch so, else ``result``'s; None for box onto box only. One laying per
    orientation, whatever m: an answer at a small m pairs too few regions to lay the sketch, and
    a flow per m would cost an evaluation's sweep a flow per m."""
    if not laid_by_answer(prepared.config):
        return None
    chosen = prepared.chosen
    if chosen is not None and tuple(chosen.orientation) == tuple(orientation) and chosen.pairs:
        return list(chosen.pairs)
    return list(result.pairs) if result is not None and result.pairs else None


def window_rule(config) -> str:
    """How ``config`` (a :class:`~ursim_core.matching.MatchConfig`) lays the sketch in the metric
    map's best window (``elastic_laying``, :data:`~ursim_core.matching.config.ELASTIC_LAYING_RULES`):
    'off', 'clear' (when clearly better than box onto box) or 'competes' (whichever lands more)."""
    return ELASTIC_LAYING_RULES[config.elastic_laying][0]


def laid_by_answer(config) -> bool:
    """Whether ``config`` also lays the sketch by the planar answer's pairs (``elastic_laying``)."""
    return ELASTIC_LAYING_RULES[config.elastic_laying][1]


def _lay(sketch_labels, metric_labels, orientation, min_iou: float, answer=None, *, window: str = "off"):
    from ursim_core.matching.elastic import lay_sketch

    degrees, mirrored = orientation
    return lay_sketch(
        sketch_labels,
        metric_labels,
        degrees=degrees,
        mirrored=mirrored,
        answer=answer,
        window=window != "off",
        window_competes=window == "competes",
        min_iou=min_iou,
    )


def laid_in(prepared: Prepared, orientation: tuple, result: MatchResult | None = None):
    """The sketch laid and bent onto the metric map in ``orientation``
    (:class:`~ursim_core.matching.elastic.LaidSketch`, or None when either map has no region):
    found once per orientation and kept in ``Prepared.elastic_answers`` (waited for when it was
    laid ahead); ``result``'s pairs lay it too with a laying by the answer (:func:`laying_answer`)."""
    answers = prepared.elastic_answers
    if isinstance(answers.get(orientation), LaidAhead):
        answers[orientation] = answers[orientation].laid()
    if orientation not in answers:
        answers[orientation] = _lay(
            prepared.sketch_labels,
            prepared.metric_labels,
            orientation,
            prepared.config.overlay_min_iou,
            laying_answer(prepared, orientation, result),
            window=window_rule(prepared.config),
        )
    return answers[orientation]


def joined_partners(overlaps: dict, metric_graph, *, preferred=()) -> list:
    """The pairs of ``overlaps`` (``{(sketch region, metric region): intersection over union}``)
    in which a sketch region paired with several metric regions keeps one and those joined to a
    kept one by an edge of ``metric_graph`` (``MatchConfig.elastic_partners``).

    The one kept first is its partner in ``preferred`` (the graph answer's pairs: the structure
    agrees with it) when it has one there, else the one it overlaps most. A drawn room bent over
    two of the map's rooms with a wall between (a partial sketch stretched past its end, a room
    drawn too large) belongs to one of them; over two regions that touch (a room or corridor the
    map's segmentation splits) it may be both. Round 53 (docs/studies.md): generated partial
    sketches 0.833 -> 0.848 mean F1; KTH unchanged in the 8 orientations, 0.811 -> 0.814 at free
    angles.

    Examples
    --------
    >>> import networkx as nx
    >>> metric = nx.Graph([(1, 2)]); metric.add_nodes_from([3, 4])
    >>> overlaps = {(1, 1): 0.5, (1, 2): 0.3, (1, 3): 0.2, (2, 3): 0.6, (2, 4): 0.4}
    >>> joined_partners(overlaps, metric)
    [(1, 1), (1, 2), (2, 3)]
    >>> joined_partners(overlaps, metric, preferred=[(2, 4)])
    [(1, 1), (1, 2), (2, 4)]
    """
    preferred = set(preferred)
    partners: dict = {}
    for sketch_region, metric_region in overlaps:
        partners.setdefault(sketch_region, []).append(metric_region)
    kept = []
    for sketch_region, found in partners.items():
        # The graph answer's partner, then by overlap; ties by region id, so that the answer does
        # not depend on the order of ``overlaps``.
        found.sort(
            key=lambda region: ((sketch_region, region) not in preferred, -overlaps[sketch_region, region], region)
        )
        joined, left = found[:1], found[1:]
        while left:
            near = [region for region in left if any(metric_graph.has_edge(region, other) for other in joined)]
            if not near:
                break
            joined += near
            left = [region for region in left if region not in near]
        kept += [(sketch_region, metric_region) for metric_region in joined]
    return sorted(kept)


def laid_elastically(prepared: Prepared, result: MatchResult) -> MatchResult:
    """``result`` with the pairs of the sketch laid elastically in its orientation
    (``MatchConfig.elastic``, :mod:`ursim_core.matching.elastic`), within the constraints; with
    ``MatchConfig.elastic_laying='boxes_or_answer'`` laid box onto box or by the planar answer's
    pairs (:func:`laying_answer`), whichever lands more on the metric map's free space once bent."""
    from ursim_core.matching.overlay import constrained_pairs

    laid = laid_in(prepared, tuple(result.orientation), result)
    if laid is None:
        pairs = []
    elif prepared.config.elastic_partners == "neighbours":
        pairs = joined_partners(laid.overlaps, prepared.metric_graph, preferred=result.pairs)
    else:
        pairs = laid.pairs
    if prepared.config.elastic == "completed":
        # Regions the overlay leaves alone on both sides keep the graph answer's pairs: a small
        # region the bent sketch misses still has its partner (a stub, a cut-off room).
        sketch_paired, metric_paired = {a for a, _ in pairs}, {b for _, b in pairs}
        pairs = sorted(
            set(pairs) | {(a, b) for a, b in result.pairs if a not in sketch_paired and b not in metric_paired}
        )
    pairs = constrained_pairs(pairs, prepared.constraints)
    return replaced(result, pairs=pairs, laid=True, laying=None if laid is None else laid.laying)
