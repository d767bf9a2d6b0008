"""Sketches of part of the metric map in the matching pipeline.

A sketch may show only part of the building. Its positions, normalised by each map's extent,
then stretch it over the whole map. Read rightly, it resembles a part of the map clearly better
than the whole (:func:`~ursim_core.matching.template.best_window`). Three uses of that window,
for :func:`~ursim_core.matching.pipeline.prepare`:

- :func:`reading_windows`: each finalist reading's window, for ``MatchConfig.window_reading_margin``
  (the reading in which the sketch resembles a part of the map clearly better is taken);
- :func:`window_starts_of`: the sketch's positions laid in that window, one more start of the
  position refit (``MatchConfig.window_start``); the two share one window search per finalist;
- :func:`looks_partial`: whether a sketch matched with the default options is laid in a window,
  and is to be matched again as a partial sketch (``MatchConfig.auto_partial``, :data:`PARTIAL_NOTE`).
"""

from __future__ import annotations

from ursim_core.matching.config import PARTIAL_SKETCH
from ursim_core.matching.laid import elastic_labels, laid_by_answer, laid_in, sketch_sized_labels, window_rule
from ursim_core.matching.oriented import (
    carried_by_orientation,
    finalist_windows,
    turned_windows,
    window_position_starts,
)
from ursim_core.matching.results import Prepared

__all__ = ["PARTIAL_NOTE", "looks_partial", "reading_windows", "window_starts_of"]

#: The reason an answer matched again as a sketch of part of the map carries (``auto_partial``).
PARTIAL_NOTE = "read as a sketch of part of the map: it resembles part of the map clearly better than the whole"


def looks_partial(prepared: Prepared) -> bool:
    """Whether ``prepared`` (the sketch's labels kept for the elastic answer) should be matched
    again as a partial sketch (``MatchConfig.auto_partial``): the sketch, in the reading its
    answer will be in, is laid in a window of the metric map. That laying is what the elastic
    answer computes first anyway, in the same reading, so it is kept in
    ``Prepared.elastic_answers`` for it. Never when the options are already a partial sketch's,
    or lay the sketch by the answer (its laying then depends on m)."""
    config = prepared.config
    if not config.auto_partial or window_rule(config) == "off" or laid_by_answer(config):
        return False
    if all(getattr(config, name) == value for name, value in PARTIAL_SKETCH.items()):
        return False
    reading = prepared.resampled.reading if prepared.resampled is not None else None
    orientation = tuple(reading.orientation) if reading is not None else tuple(prepared.orientation)
    laid = laid_in(prepared, orientation)
    return laid is not None and laid.laying is not None and laid.laying.by == "window"


def reading_windows(
    base: Prepared, sketch_seg, metric_seg, candidates, indices, measured, searched=None, *, largest: int
) -> dict:
    """By candidate index, its best window's ``(correlation, gain)`` (or None): carried from
    ``measured`` (another segmentation's) when given, else found, or taken from ``searched``
    (:func:`~ursim_core.matching.oriented.turned_windows` found for the window starts); ``{}`` for
    bare graphs and maps of more than ``largest`` regions, which are not laid. (Found on a thread
    while the finalists were matched, they cost as much: the two compete for the same two cores;
    round 48.)"""
    if measured:
        carried = carried_by_orientation(measured, candidates, indices)
        if carried is not None:
            return carried
    labels = elastic_labels(base, sketch_seg, metric_seg, largest=largest)
    if labels is None:
        return {}
    found = finalist_windows(*labels, [candidates[index] for index in indices], searched=searched)
    return {index: found[candidates[index]] for index in indices}


def window_starts_of(
    config, sketch_seg, metric_seg, candidates, preparations, indices, measured, *, refits: bool, largest: int
) -> tuple[dict, dict]:
    """By candidate index, the laying of its sketch's positions in its best window
    (``MatchConfig.window_start``, :func:`~ursim_core.matching.oriented.window_position_starts`)
    or None: carried from ``measured`` (another segmentation's) when given, else found; ``{}``
    without the option, a position refit (``refits``), label images, or for maps of more than
    ``largest`` regions. With the windows found, by
    orientation (:func:`~ursim_core.matching.oriented.turned_windows`; ``{}`` when carried), for
    the reading's windows to reuse."""
    if not config.window_start or not refits:
        return {}, {}
    if measured:
        carried = carried_by_orientation(measured, candidates, list(indices))
        if carried is not None:
            return carried, {}
    labels = sketch_sized_labels(preparations[next(iter(indices))], sketch_seg, metric_seg, largest=largest)
    if labels is None:
        return {}, {}
    sketch_labels, metric_labels = labels
    searched = turned_windows(sketch_labels, metric_labels, [candidates[index] for index in indices])
    found = window_position_starts(
        sketch_labels, metric_labels, {candidates[index]: preparations[index] for index in indices}, searched=searched
    )
    return {index: found[candidates[index]] for index in indices}, searched
