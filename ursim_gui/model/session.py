"""The annotation session: maps, segmentations, correspondences, undo history, evaluation.

This is the whole state of one URSIM Studio window, without Qt. Widgets read its
properties, call its methods and repaint when its signals fire; tests drive it
directly.

Design
------
- The correspondences are one immutable :class:`~ursim_core.correspondences.Correspondences`
  value. Every edit builds a new value and records ``(description, before, after)`` in a
  :class:`~ursim_gui.model.history.History`, so undo/redo restore exact values.
- ``dirty`` is not a flag that edits set: it is ``correspondences != saved value``, so
  undoing back to what is on disk makes the document clean again.
- Clicked points are authoritative, region ids are derived: a new segmentation
  re-derives every clique's regions (in the current value *and* in every history value,
  so undo keeps working after re-segmenting).
- No wall-clock: the only time the session reads is the ``created``/``modified``
  timestamp written on save, through the injectable ``timestamp`` callable.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ursim_core.correspondences import Clique, Correspondences, MapRef, utc_timestamp
from ursim_core.correspondences.exporters import clique_label
from ursim_core.errors import SegmentationError
from ursim_gui.model.history import History
from ursim_gui.model.read_ahead import MapReadAhead
from ursim_gui.model.session_documents import DocumentOperations
from ursim_gui.model.session_edits import EditOperations
from ursim_gui.model.session_evaluation import EvaluationOperations
from ursim_gui.model.session_label_edits import EDITED_METHOD, LabelEditOperations
from ursim_gui.model.session_selection import SelectionOperations
from ursim_gui.model.session_values import (
    APP_TITLE,
    AUTOSAVE_ORIGIN_KEY,
    DEFAULT_PRESETS,
    REFERENCE_TOLERANCE,
    SIDES,
    _absolute,
    _check_side,
    _regions_text,
    _with_side_regions,
    color_of_clique,
)
from ursim_gui.model.signals import Signal
from ursim_gui.model.view_state import laid_sketch_of

__all__ = [
    "SIDES",
    "APP_TITLE",
    "REFERENCE_TOLERANCE",
    "DEFAULT_PRESETS",
    "AUTOSAVE_ORIGIN_KEY",
    "AnnotationSession",
    "color_of_clique",
]


def _untouched_automatic(clique: Clique) -> bool:
    return clique.source == "auto" and clique.status is None and not clique.note and clique_label(clique) is None


class AnnotationSession(
    SelectionOperations, DocumentOperations, EditOperations, EvaluationOperations, LabelEditOperations
):
    """State and operations of one annotation window (Qt-free).

    Parameters
    ----------
    annotator : str, keyword-only
        Written into new documents.
    timestamp : callable, keyword-only
        ``() -> str`` ISO-8601 UTC time used for ``created``/``modified`` on save;
        tests inject a fixed one.

    Attributes
    ----------
    map_changed, segmentation_changed : Signal
        ``(side)``.
    correspondences_changed, selection_changed, reference_changed, history_changed : Signal
        No arguments.
    dirty_changed : Signal
        ``(dirty: bool)``, only when the value flips.
    path_changed : Signal
        ``(path: Path | None)``.
    document_opened : Signal
        ``(correspondences)``: a document was opened from a file or recovered, after its maps
        and cliques are in place (what the file says about how it was made can be read back).
    error : Signal
        ``(message: str)`` for problems found while an operation still succeeded (e.g. a
        map file that changed since the correspondences were saved). Failures of an
        operation are raised instead, for the caller to show.

    Notes
    -----
    Undoable operations record exactly one history entry when they change the
    correspondences and none when they would not change anything (linking regions that
    are already in the clique, unlinking a region no clique has, setting the status a
    clique already has): an undo step that does nothing visible would only confuse.
    """

    def __init__(self, *, annotator: str = "", timestamp: Callable[[], str] = utc_timestamp) -> None:
        self.map_changed = Signal("map_changed")
        self.segmentation_changed = Signal("segmentation_changed")
        self.correspondences_changed = Signal("correspondences_changed")
        self.selection_changed = Signal("selection_changed")
        self.dirty_changed = Signal("dirty_changed")
        self.path_changed = Signal("path_changed")
        self.document_opened = Signal("document_opened")
        self.reference_changed = Signal("reference_changed")
        self.history_changed = Signal("history_changed")
        self.error = Signal("error")

        self._timestamp = timestamp
        #: Annotator of the documents :meth:`new_document` starts.
        self.annotator = annotator
        self._maps: dict[str, Any] = {side: None for side in SIDES}
        #: Map files read ahead on a thread (a campaign's next pairs); every map is read through it.
        self.read_ahead = MapReadAhead()
        self._segmentations: dict[str, Any] = {side: None for side in SIDES}
        self._no_region_reasons: dict[str, tuple[Any, str]] = {}  # side -> (segmentation, reason)
        self._presets = dict(DEFAULT_PRESETS)
        self._corr = Correspondences(annotator=annotator)
        self._saved: Correspondences | None = self._corr
        self._path: Path | None = None
        self._history: History[Correspondences] = History()
        self._selection: dict[str, frozenset[int]] = {side: frozenset() for side in SIDES}
        self._selected_clique: int | None = None
        self._focus: tuple[str, int] | None = None
        self._reference_corr: Correspondences | None = None
        self._reference_path: Path | None = None
        # PNG files written for drawn maps (session_documents.drawn_maps_beside): path -> (map, sha256).
        self._drawn_files: dict[Path, tuple[Any, str]] = {}
        self._reference: list[tuple[frozenset[int], frozenset[int]]] | None = None
        self._evaluation = None
        self._clique_marks: dict[int, str] = {}
        self._last_match = None
        # ((match, sketch labels, metric labels), laid sketch): see laid_sketch.
        self._laid: tuple | None = None
        self._anchors: list[tuple[int, int]] = []
        self._match_config = None
        self._label_versions: dict = {}
        self._label_edit_count = 0

    # ------------------------------------------------------------------ read-only state
    def map(self, side: str):
        """The ``ursim_core.io.maps.Map`` of ``side``, or None."""
        return self._maps[_check_side(side)]

    def segmentation(self, side: str):
        """The ``ursim_core.segmentation.Segmentation`` of ``side``, or None."""
        return self._segmentations[_check_side(side)]

    def no_region_reason(self, side: str) -> str | None:
        """Why the segmentation of ``side`` has no region (``why_no_region``), or None when it
        has regions or there is no map or segmentation; worked out once per segmentation (the
        status bar and the segmentation panel both say it)."""
        segmentation, map_ = self.segmentation(side), self._maps[side]
        if segmentation is None or map_ is None or segmentation.n_regions != 0:
            return None
        known = self._no_region_reasons.get(side)  # dropped whenever the segmentation changes
        if known is None or known[0] is not segmentation:
            from ursim_core.segmentation import why_no_region

            known = (segmentation, why_no_region(map_.free, method=segmentation.method))
            self._no_region_reasons[side] = known
        return known[1]

    def segmentation_preset(self, side: str) -> str:
        """Preset name the segmentation panel offers for ``side``."""
        return self._presets[_check_side(side)]

    def set_segmentation_preset(self, side: str, preset: str) -> None:
        """Remember the preset chosen for ``side`` (used by the next segmentation job)."""
        self._presets[_check_side(side)] = str(preset)

    @property
    def correspondences(self) -> Correspondences:
        return self._corr

    @property
    def saved_correspondences(self) -> Correspondences | None:
        """The value last saved or opened (what ``dirty`` compares against)."""
        return self._saved

    @property
    def path(self) -> Path | None:
        return self._path

    @property
    def dirty(self) -> bool:
        """True when closing would lose work: the correspondences differ from the saved ones.

        An untitled document whose cliques are all untouched matcher output (automatic,
        never reviewed, no note), whose segmentations are not hand-edited and whose maps all have
        files is never dirty: it holds nothing that re-opening and re-matching the two maps would
        not restore, so quitting it need not ask. A merged, split or painted segmentation and a
        sketch drawn in the app are the user's work.
        """
        if (
            self._path is None
            and not any(getattr(self._corr, side).segmentation_method == EDITED_METHOD for side in SIDES)
            and not any(map_ is not None and map_.path is None for map_ in self._maps.values())
            and all(_untouched_automatic(clique) for clique in self._corr.cliques)
        ):
            return False
        return self._corr != self._saved

    @property
    def anchors(self) -> list[tuple[int, int]]:
        """(sketch region, metric region) anchor pairs of the last match."""
        return list(self._anchors)

    @property
    def last_match(self):
        return self._last_match

    def laid_sketch(self):
        """The sketch's regions where the last match laid them, on the metric map's pixels
        (:func:`~ursim_gui.model.view_state.laid_sketch_of`); None without one.

        Made once per match and pair of label images; the app's match job makes it in the
        worker and hands it over with the match (:meth:`apply_match`), so the GUI thread does
        not compute the laying's flow (20-30 ms for a KTH pair).
        """
        sketch, metric = self._segmentations["sketch"], self._segmentations["metric"]
        if self._last_match is None or sketch is None or metric is None:
            return None
        made_of = (self._last_match, sketch.labels, metric.labels)
        if self._laid is None or any(a is not b for a, b in zip(self._laid[0], made_of)):
            self._laid = (made_of, laid_sketch_of(*made_of))
        return self._laid[1]

    @property
    def match_config(self):
        """The ``ursim_core.matching.MatchConfig`` the next match uses (core defaults at first)."""
        if self._match_config is None:
            from ursim_core.matching import MatchConfig

            self._match_config = MatchConfig()
        return self._match_config

    @match_config.setter
    def match_config(self, config) -> None:
        self._match_config = config

    @property
    def reference(self) -> list[tuple[frozenset[int], frozenset[int]]] | None:
        """Reference cliques as (sketch regions, metric regions), or None when none is loaded."""
        return None if self._reference is None else list(self._reference)

    @property
    def reference_correspondences(self) -> Correspondences | None:
        """The reference as loaded (points and file regions)."""
        return self._reference_corr

    @property
    def reference_path(self) -> Path | None:
        """The file the reference was loaded from, or None when none is loaded."""
        return self._reference_path

    @property
    def evaluation(self):
        """``ursim_core.evaluation.scoring.MatchScore`` of the non-rejected cliques, or None."""
        return self._evaluation

    @property
    def history(self) -> History[Correspondences]:
        """The undo history (read it; change it only through the session's operations)."""
        return self._history

    @property
    def can_undo(self) -> bool:
        return self._history.can_undo

    @property
    def can_redo(self) -> bool:
        return self._history.can_redo

    @property
    def undo_text(self) -> str:
        return self._history.undo_text

    @property
    def redo_text(self) -> str:
        return self._history.redo_text

    def window_title(self) -> str:
        """``'URSIM Studio — name.json*'``: the file name ('untitled' without one), ``*`` when dirty."""
        name = self._path.name if self._path is not None else "untitled"
        return f"{APP_TITLE} — {name}{'*' if self.dirty else ''}"

    # ------------------------------------------------------------------ queries for views
    def clique(self, clique_id: int) -> Clique:
        """The clique with this id (KeyError when there is none)."""
        return self._corr.clique(clique_id)

    def clique_of(self, side: str, region: int) -> list[int]:
        """Ids of the cliques that contain ``region`` on ``side``, in clique order."""
        field_name = f"{_check_side(side)}_regions"
        return [clique.id for clique in self._corr.cliques if region in getattr(clique, field_name)]

    def partners(self, side: str, region: int) -> frozenset[int]:
        """Regions of the other side in the cliques that contain ``region`` (hover highlight)."""
        other = SIDES[1 - SIDES.index(_check_side(side))]
        own_field, other_field = f"{side}_regions", f"{other}_regions"
        return frozenset(
            partner
            for clique in self._corr.cliques
            if region in getattr(clique, own_field)
            for partner in getattr(clique, other_field)
        )

    def color_of_clique(self, clique_id: int) -> tuple[int, int, int]:
        """See :func:`color_of_clique`."""
        return color_of_clique(clique_id)

    # ------------------------------------------------------------------ maps and segmentations
    def load_map(self, side: str, path: str | os.PathLike) -> None:
        """Load a map file for ``side`` (raises ``UrsimError``; the session is unchanged then);
        the map read ahead when it was (:attr:`read_ahead`)."""
        self.set_map(side, self.read_map(path))

    def read_map(self, path: str | os.PathLike):
        """The map of ``path``, read (or taken from :attr:`read_ahead`) without showing it: a
        command that replaces the document reads first, so a file that fails leaves the work."""
        return self.read_ahead.read(_absolute(path))

    def set_map(self, side: str, map_) -> None:
        """Show ``map_`` on ``side``; its segmentation is dropped (it belonged to the old map).

        The cliques are kept, with their points; their region ids on this side come back
        from the points when the new map is segmented. The map reference is updated in the
        whole history, so undo never brings back the old map's reference.
        """
        _check_side(side)
        path = None if map_.path is None else _absolute(map_.path)
        old_ref: MapRef = getattr(self._corr, side)
        new_ref = dataclasses.replace(
            old_ref,
            path=path,
            sha256=map_.sha256,
            size=tuple(map_.shape),
            segmentation_method=None,
            segmentation_params={},
            labels_path=None,
        )

        def rebase(value: Correspondences) -> Correspondences:
            return dataclasses.replace(value, **{side: new_ref})

        was_dirty = self.dirty
        self._maps[side] = map_
        self._segmentations[side] = None
        self._no_region_reasons.pop(side, None)  # and the old label image it holds
        self._forget_match()
        self._history.map_values(rebase)
        self._corr = rebase(self._corr)
        selection_cleared = self._clear_side_selection(side)
        self._recompute_reference()
        self._evaluate()
        self.map_changed.emit(side)
        self.segmentation_changed.emit(side)
        if selection_cleared:
            self.selection_changed.emit()
        self._announce_value_change(was_dirty)
        self.history_changed.emit()

    def set_segmentation(self, side: str, segmentation) -> None:
        """Use ``segmentation`` for ``side`` and re-derive every clique's region ids from its points.

        Raises
        ------
        SegmentationError
            The label image's size differs from the map's.
        """
        _check_side(side)
        shape = tuple(segmentation.labels.shape)
        map_ = self._maps[side]
        if map_ is not None and tuple(map_.shape) != shape:
            raise SegmentationError(
                f"the {side} label image is {shape[0]}x{shape[1]} but the {side} map is "
                f"{map_.shape[0]}x{map_.shape[1]} (rows x cols)",
                path=segmentation.source,
            )
        old_ref: MapRef = getattr(self._corr, side)
        new_ref = dataclasses.replace(
            old_ref,
            size=old_ref.size or shape,
            segmentation_method=segmentation.method,
            segmentation_params=dict(segmentation.params),
            labels_path=None if segmentation.source is None else _absolute(segmentation.source),
        )
        labels = segmentation.labels

        def rebase(value: Correspondences) -> Correspondences:
            return _with_side_regions(dataclasses.replace(value, **{side: new_ref}), side, labels)

        was_dirty = self.dirty
        if (
            self._path is not None
            and self._saved is not None
            and getattr(self._saved, side).segmentation_method is None
        ):
            # The file records no segmentation of this map (ground truth clicked on another
            # tool's regions, say): any segmentation agrees with it, and segmenting is no edit.
            self._saved = rebase(self._saved)
        self._segmentations[side] = segmentation
        self._no_region_reasons.pop(side, None)
        # The last match's anchors and pairs name regions of the old segmentation.
        self._forget_match()
        self._history.map_values(rebase)
        self._corr = rebase(self._corr)
        # Region ids of the old segmentation mean nothing now.
        selection_cleared = self._clear_side_selection(side)
        self._recompute_reference()
        self._evaluate()
        self.segmentation_changed.emit(side)
        if selection_cleared:
            self.selection_changed.emit()
        self._announce_value_change(was_dirty)
        self.history_changed.emit()

    def undo(self) -> bool:
        """Undo the last edit; False when there is nothing to undo."""
        if not self._history.can_undo:
            return False
        self._replace_value(self._history.undo())
        self.history_changed.emit()
        return True

    def redo(self) -> bool:
        """Redo the last undone edit; False when there is nothing to redo."""
        if not self._history.can_redo:
            return False
        self._replace_value(self._history.redo())
        self.history_changed.emit()
        return True

    # ------------------------------------------------------------------ internals
    def _forget_match(self) -> None:
        self._last_match = None
        self._laid = None
        self._anchors = []

    def _commit(self, description: str, new: Correspondences) -> bool:
        """Apply one undoable edit: a history entry and the signals. False when nothing changed."""
        if new == self._corr:
            return False
        self._history.push(description, self._corr, new)
        self._replace_value(new)
        self.history_changed.emit()
        return True

    def _replace_value(self, new: Correspondences) -> None:
        was_dirty = self.dirty
        self._corr = new
        self._sync_segmentations()
        selection_changed = False
        if self._selected_clique is not None and not any(c.id == self._selected_clique for c in new.cliques):
            self._selected_clique = None
            self._focus = None
            selection_changed = True
        self._evaluate()
        if selection_changed:
            self.selection_changed.emit()
        self._announce_value_change(was_dirty)

    def _announce_value_change(self, was_dirty: bool) -> None:
        self.correspondences_changed.emit()
        if self.dirty != was_dirty:
            self.dirty_changed.emit(self.dirty)

    def _checked_regions(self, side: str, regions: Iterable[int], *, stale_hint: bool = False) -> tuple[int, ...]:
        chosen = tuple(dict.fromkeys(int(region) for region in regions))
        if not chosen:
            return ()
        segmentation = self._segmentations[side]
        if segmentation is None:
            raise ValueError(f"the {side} map is not segmented")
        unknown = [region for region in chosen if region not in segmentation.graph]
        if unknown:
            hint = " (a result computed before the map was re-segmented?)" if stale_hint else ""
            raise ValueError(f"{side} region(s) {_regions_text(unknown)} not in the current segmentation{hint}")
        return chosen

    def _interior_points(self, side: str, regions: Iterable[int]) -> tuple[tuple[int, int], ...]:
        graph = self._segmentations[side].graph if regions else None
        return tuple(tuple(int(v) for v in graph.nodes[region]["interior"]) for region in regions)

    def _with_regions_from_points(self, corr: Correspondences) -> Correspondences:
        for side in SIDES:
            segmentation = self._segmentations[side]
            if segmentation is not None:
                corr = _with_side_regions(corr, side, segmentation.labels)
        return corr
