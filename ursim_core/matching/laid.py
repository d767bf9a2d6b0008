"""The elastic answer in the matching pipeline (``MatchConfig.elastic``).

The planar matcher reads the sketch's orientation and votes over its segmentations; the answer's
pairs are then those of the sketch laid and bent onto the metric map in that orientation
(:mod:`ursim_core.matching.elastic`), completed by the planar answer's pairs of regions left
unpaired on both sides ('completed'), within a person's constraints. :func:`prepare
<ursim_core.matching.prepare>` starts the first segmentation's laying on a thread
(:class:`LaidAhead`) while the other segmentations are prepared.
"""

from __future__ import annotations

from ursim_core.matching.results import MatchResult, Prepared, replaced

__all__ = ["elastic_labels", "LaidAhead", "laid_elastically"]


def elastic_labels(prepared: Prepared, sketch_seg, metric_seg, *, largest: int) -> tuple | None:
    """The two label images when the answer's pairs are to be the laid sketch's (``MatchConfig.elastic``):
    the planar matcher, segmentations, and at most ``largest`` regions a map."""
    if prepared.config.elastic == "off" or prepared.config.matcher != "planar":
        return None
    sketch_labels, metric_labels = getattr(sketch_seg, "labels", None), getattr(metric_seg, "labels", None)
    # Sketch-sized maps only: at the working size (512 px) a building's thousands of regions
    # would be a few pixels wide, and its graph answer is not screened by orientation alike.
    if sketch_labels is None or metric_labels is None or max(prepared.c_matrix.shape) > largest:
        return None
    return sketch_labels, metric_labels


class LaidAhead:
    """:func:`~ursim_core.matching.elastic.elastic_pairs` of one orientation, run on a thread from
    the start; :meth:`pairs` waits for it. The same pairs as a call made later (no shared state
    but the metric map's memo of its working image)."""

    def __init__(self, sketch_labels, metric_labels, orientation, min_iou: float) -> None:
        import threading

        self._pairs: list | None = None
        self._error: BaseException | None = None
        arguments = (sketch_labels, metric_labels, orientation, min_iou)
        self._thread = threading.Thread(target=self._run, args=arguments, daemon=True)
        self._thread.start()

    def _run(self, sketch_labels, metric_labels, orientation, min_iou) -> None:
        try:
            self._pairs = _elastic_pairs_of(sketch_labels, metric_labels, orientation, min_iou)
        except BaseException as error:  # re-raised where the pairs are read
            self._error = error

    def pairs(self) -> list:
        self._thread.join()
        if self._error is not None:
            raise self._error
        return self._pairs


def _elastic_pairs_of(sketch_labels, metric_labels, orientation, min_iou: float) -> list:
    from ursim_core.matching.elastic import elastic_pairs

    degrees, mirrored = orientation
    return elastic_pairs(sketch_labels, metric_labels, degrees=degrees, mirrored=mirrored, min_iou=min_iou)


def laid_elastically(prepared: Prepared, result: MatchResult) -> MatchResult:
    """``result`` with the pairs of the sketch laid elastically in its orientation
    (``MatchConfig.elastic``, :mod:`ursim_core.matching.elastic`), within the constraints."""
    from ursim_core.matching.overlay import constrained_pairs

    orientation = tuple(result.orientation)
    answers = prepared.elastic_answers
    if isinstance(answers.get(orientation), LaidAhead):
        answers[orientation] = answers[orientation].pairs()
    if orientation not in answers:
        answers[orientation] = _elastic_pairs_of(
            prepared.sketch_labels, prepared.metric_labels, orientation, prepared.config.overlay_min_iou
        )
    pairs = answers[orientation]
    if prepared.config.elastic == "completed":
        # Regions the overlay leaves alone on both sides keep the graph answer's pairs: a small
        # region the bent sketch misses still has its partner (a stub, a cut-off room).
        sketch_paired, metric_paired = {a for a, _ in pairs}, {b for _, b in pairs}
        pairs = sorted(
            set(pairs) | {(a, b) for a, b in result.pairs if a not in sketch_paired and b not in metric_paired}
        )
    pairs = constrained_pairs(pairs, prepared.constraints)
    return replaced(result, pairs=pairs, laid=True)
