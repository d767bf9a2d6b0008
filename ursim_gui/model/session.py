"""The annotation session: maps, segmentations, correspondences, undo history, evaluation.

This is the whole state of one URSIM Studio window, without Qt. Widgets read its
properties, call its methods and repaint when its signals fire; tests drive it
directly.

Design
------
- The correspondences are one immutable :class:`~ursim_core.correspondences.codec.Correspondences`
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

import colorsys
import dataclasses
import os
from collections.abc import Callable, Iterable
from itertools import product
from pathlib import Path
from typing import Any

from ursim_core.correspondences.codec import (
    STATUSES,
    Clique,
    Correspondences,
    MapRef,
    from_pairs,
    load_correspondences,
    load_dat,
    regions_at_points,
    save_correspondences,
    save_dat,
    utc_timestamp,
)
from ursim_core.errors import SegmentationError, UrsimError
from ursim_core.matching import MATCH_PRESETS
from ursim_gui.model.history import History
from ursim_gui.model.signals import Signal

__all__ = [
    "SIDES",
    "APP_TITLE",
    "REFERENCE_TOLERANCE",
    "DEFAULT_PRESETS",
    "AUTOSAVE_ORIGIN_KEY",
    "AnnotationSession",
    "color_of_clique",
]

SIDES = ("sketch", "metric")
APP_TITLE = "URSIM Studio"
#: Pixels a reference point may lie off a region and still count for it (the released code's value).
REFERENCE_TOLERANCE = 10
#: Segmentation preset a side starts with.
DEFAULT_PRESETS = dict(MATCH_PRESETS)
#: Top-level key of an autosave file naming the document it belongs to (see autosave.py).
AUTOSAVE_ORIGIN_KEY = "autosave_of"

_GOLDEN_RATIO_CONJUGATE = 0.618033988749895
_STATUS_VERBS = {"accepted": "Accept", "rejected": "Reject", "pending": "Mark pending"}


def color_of_clique(clique_id: int) -> tuple[int, int, int]:
    """Deterministic, well separated ``(r, g, b)`` colour of a clique (ints 0..255).

    Hues step by the golden ratio so neighbouring ids never look alike; saturation and
    value cycle over three levels so hues that come round again stay distinct. The
    formula is the one of ``ursim_gui.overlay.clique_colour`` so the table, the maps and
    exported figures agree (a test checks it).

    Examples
    --------
    >>> color_of_clique(1) == color_of_clique(1), color_of_clique(1) != color_of_clique(2)
    (True, True)
    """
    index = int(clique_id)
    hue = (0.08 + index * _GOLDEN_RATIO_CONJUGATE) % 1.0
    saturation = (0.75, 0.55, 0.9)[index % 3]
    value = (0.95, 0.8, 0.7)[(index // 3) % 3]
    r, g, b = colorsys.hsv_to_rgb(hue, saturation, value)
    return int(round(r * 255)), int(round(g * 255)), int(round(b * 255))


def _absolute(path: str | os.PathLike) -> Path:
    # Normalised the way load_correspondences returns paths, so a saved and re-loaded
    # document compares equal to the value in memory.
    return Path(os.path.normpath(os.path.abspath(path)))


def _check_side(side: str) -> str:
    if side not in SIDES:
        raise ValueError(f"side must be one of {SIDES}, got {side!r}")
    return side


def _regions_text(regions: Iterable[int]) -> str:
    return ", ".join(str(region) for region in regions) or "-"


def _with_side_regions(corr: Correspondences, side: str, labels) -> Correspondences:
    """Re-derive one side's region ids of every clique from its points.

    Same rule as :func:`ursim_core.correspondences.codec.assign_regions` (ids under the points,
    tolerance 10, duplicates and dropped points left out, point order), for one side only,
    because the other side may not be segmented yet.
    """
    point_lists = [getattr(clique, f"{side}_points") for clique in corr.cliques]
    found = iter(
        regions_at_points(labels, [p for points in point_lists for p in points], tolerance=REFERENCE_TOLERANCE)
    )
    cliques = []
    for clique, points in zip(corr.cliques, point_lists):
        ids = tuple(dict.fromkeys(region for region in (next(found) for _ in points) if region != 0))
        cliques.append(dataclasses.replace(clique, **{f"{side}_regions": ids}))
    return corr.with_cliques(cliques)


class AnnotationSession:
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
        self.reference_changed = Signal("reference_changed")
        self.history_changed = Signal("history_changed")
        self.error = Signal("error")

        self._timestamp = timestamp
        self._maps: dict[str, Any] = {side: None for side in SIDES}
        self._segmentations: dict[str, Any] = {side: None for side in SIDES}
        self._presets = dict(DEFAULT_PRESETS)
        self._corr = Correspondences(annotator=annotator)
        self._saved: Correspondences | None = self._corr
        self._path: Path | None = None
        self._history: History[Correspondences] = History()
        self._selection: dict[str, frozenset[int]] = {side: frozenset() for side in SIDES}
        self._selected_clique: int | None = None
        self._reference_corr: Correspondences | None = None
        self._reference: list[tuple[frozenset[int], frozenset[int]]] | None = None
        self._evaluation = None
        self._clique_marks: dict[int, str] = {}
        self._last_match = None
        self._anchors: list[tuple[int, int]] = []
        self._match_config = None

    # ------------------------------------------------------------------ read-only state
    def map(self, side: str):
        """The ``ursim_core.io.maps.Map`` of ``side``, or None."""
        return self._maps[_check_side(side)]

    def segmentation(self, side: str):
        """The ``ursim_core.segmentation.Segmentation`` of ``side``, or None."""
        return self._segmentations[_check_side(side)]

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

        An untitled document without cliques is never dirty: it holds nothing that
        re-opening the two maps would not restore.
        """
        if self._path is None and not self._corr.cliques:
            return False
        return self._corr != self._saved

    @property
    def anchors(self) -> list[tuple[int, int]]:
        """(sketch region, metric region) anchor pairs of the last match."""
        return list(self._anchors)

    @property
    def last_match(self):
        return self._last_match

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
    def evaluation(self):
        """``ursim_core.evaluation.scoring.MatchScore`` of the non-rejected cliques, or None."""
        return self._evaluation

    @property
    def selection(self) -> dict[str, frozenset[int]]:
        return dict(self._selection)

    @property
    def selected_clique(self) -> int | None:
        return self._selected_clique

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

    def clique_status(self, clique_id: int) -> str | None:
        """Evaluation mark of a clique: 'tp', 'fp' or None.

        'fp' when at least one of its (sketch, metric) region pairs is in no reference
        clique, 'tp' when all are; None without a reference, for rejected cliques and for
        cliques with no region on a side (they predict no pair).
        """
        return self._clique_marks.get(clique_id)

    def missed_reference(self) -> list[int]:
        """Indices (into :attr:`reference`) of reference cliques no predicted pair hits."""
        if self._evaluation is None:
            return []
        return [index for index, label in enumerate(self._evaluation.clique_labels) if label == "missed"]

    # ------------------------------------------------------------------ maps and segmentations
    def load_map(self, side: str, path: str | os.PathLike) -> None:
        """Load a map file for ``side`` (raises ``UrsimError``; the session is unchanged then)."""
        from ursim_core.io.maps import load_map

        self.set_map(side, load_map(_absolute(path)))

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
        self._segmentations[side] = segmentation
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

    # ------------------------------------------------------------------ documents
    def open(self, path: str | os.PathLike) -> None:
        """Open a correspondence JSON with the maps it names; clears the history.

        Each map is loaded from its recorded path; its segmentation is the recorded label
        image when that file exists, else it is recomputed with the recorded method and
        parameters. Region ids are then re-derived from the points (points are
        authoritative), so the document is dirty after opening only if the file's ids
        disagreed with its points.

        Raises
        ------
        UrsimError
            The file, a map or a label image cannot be used; the message names the file
            and the problem. The session is left exactly as it was.
        """
        path = _absolute(path)
        corr = load_correspondences(path)
        self._install_document(corr, path=path, saved=corr)

    def restore(self, corr: Correspondences, *, origin: str | os.PathLike | None = None) -> None:
        """Replace the document by a recovered value (from :func:`ursim_gui.model.autosave.recover`).

        The maps it names are loaded as in :meth:`open`. The document it belongs to is
        ``origin``, or the path the autosave file recorded under ``"autosave_of"`` (that key
        is removed so it never reaches the real file). The result is dirty: it has not been
        saved, unless it equals what the original file holds.

        Raises
        ------
        UrsimError
            As :meth:`open`; the session is left unchanged.
        """
        extra = dict(corr.extra)
        recorded = extra.pop(AUTOSAVE_ORIGIN_KEY, None)
        corr = dataclasses.replace(corr, extra=extra)
        if origin is None and isinstance(recorded, str) and recorded:
            origin = recorded
        path = None if origin is None else _absolute(origin)
        saved = None
        if path is not None and path.is_file():
            try:
                saved = load_correspondences(path)
            except UrsimError:
                saved = None  # the original is unreadable: everything recovered is unsaved
        self._install_document(corr, path=path, saved=saved)

    def save(self, path: str | os.PathLike | None = None) -> None:
        """Write the correspondences to ``path`` (default: the current file), atomically.

        ``created`` (when empty) and ``modified`` are stamped. On success the document is
        clean and ``path`` becomes the current file.

        Raises
        ------
        ValueError
            No ``path`` and the document has never been saved.
        OSError, UrsimError
            Writing failed. The file on disk is unchanged, and so is the session: it
            stays dirty, with the same path.
        """
        if path is None:
            if self._path is None:
                raise ValueError("the document has no file yet: give a path to save it to")
            target = self._path
        else:
            target = _absolute(path)
        moment = self._timestamp()
        created = self._corr.created or moment
        stamped = dataclasses.replace(self._corr, created=created, modified=moment)
        save_correspondences(stamped, target, now=moment)

        was_dirty = self.dirty
        # The timestamps describe the document, not one edit: every history value gets
        # them, so undoing back to the saved content yields exactly the saved value.
        self._history.map_values(lambda value: dataclasses.replace(value, created=created, modified=moment))
        self._corr = stamped
        self._saved = stamped
        if target != self._path:
            self._path = target
            self.path_changed.emit(target)
        if self.dirty != was_dirty:
            self.dirty_changed.emit(self.dirty)
        self.history_changed.emit()

    def import_dat(self, path: str | os.PathLike) -> None:
        """Replace the cliques by those of a ``.dat`` file (one undoable step).

        The maps stay those of the session (a .dat names maps by paths relative to an
        unknown folder); region ids are derived from the points on the segmented sides.
        """
        path = _absolute(path)
        imported = load_dat(path)
        corr = self._corr.with_cliques(imported.cliques)
        corr = self._with_regions_from_points(corr)
        self._commit(f"Import {path.name}", corr)

    def export_dat(self, path: str | os.PathLike) -> None:
        """Write the cliques' points in the original ``.dat`` format (atomically)."""
        save_dat(self._corr, _absolute(path))

    def load_reference(self, path: str | os.PathLike) -> None:
        """Load reference cliques (``.json`` or ``.dat``) to evaluate the correspondences against.

        Reference regions come from the reference's points on the current segmentations
        (tolerance 10 px, as the released evaluation), or from the file's region ids on a
        side that is not segmented.
        """
        path = _absolute(path)
        reference = load_dat(path) if path.suffix.lower() == ".dat" else load_correspondences(path)
        self._reference_corr = reference
        self._recompute_reference()
        self._evaluate()
        self.reference_changed.emit()

    def clear_reference(self) -> None:
        """Stop evaluating."""
        if self._reference_corr is None:
            return
        self._reference_corr = None
        self._recompute_reference()
        self._evaluate()
        self.reference_changed.emit()

    # ------------------------------------------------------------------ selection
    def select(self, side: str, regions: Iterable[int], *, add: bool = False) -> None:
        """Select regions of ``side``.

        With ``add`` the regions join the current selection and the selected clique
        stays (so a region can be added to it); without, they replace the side's
        selection and the selected clique is cleared.
        """
        _check_side(side)
        chosen = frozenset(int(region) for region in regions)
        new_selection = dict(self._selection)
        new_selection[side] = new_selection[side] | chosen if add else chosen
        new_clique = self._selected_clique if add else None
        if new_selection == self._selection and new_clique == self._selected_clique:
            return
        self._selection = new_selection
        self._selected_clique = new_clique
        self.selection_changed.emit()

    def select_clique(self, clique_id: int | None) -> None:
        """Select a clique (its regions become the selection on both sides), or none."""
        if clique_id is None:
            if self._selected_clique is None:
                return
            self._selected_clique = None
            self.selection_changed.emit()
            return
        clique = self._corr.clique(clique_id)
        self._selected_clique = clique.id
        self._selection = {
            "sketch": frozenset(clique.sketch_regions),
            "metric": frozenset(clique.metric_regions),
        }
        self.selection_changed.emit()

    def clear_selection(self) -> None:
        """Select nothing."""
        if self._selected_clique is None and not any(self._selection.values()):
            return
        self._selection = {side: frozenset() for side in SIDES}
        self._selected_clique = None
        self.selection_changed.emit()

    # ------------------------------------------------------------------ undoable edits
    def link(self, sketch_regions: Iterable[int], metric_regions: Iterable[int], *, into: int | None = None) -> int:
        """Link regions: a new manual clique, or add them to clique ``into``.

        Each region's anchor point is its ``interior`` point from the segmentation graph
        (a pixel safely inside it), so re-segmenting finds it again. Linking into an
        automatic clique turns it manual: a person has now vouched for it, and
        :meth:`apply_match` must not replace it.

        Returns
        -------
        int
            The id of the new (or extended) clique.

        Raises
        ------
        ValueError
            No region given, a side with regions is not segmented, or a region id is not
            in its segmentation.
        KeyError
            ``into`` is not a clique id.
        """
        sketch = self._checked_regions("sketch", sketch_regions)
        metric = self._checked_regions("metric", metric_regions)
        if not sketch and not metric:
            raise ValueError("link needs at least one region")
        if into is None:
            clique = Clique(
                id=self._corr.next_clique_id(),
                sketch_points=self._interior_points("sketch", sketch),
                metric_points=self._interior_points("metric", metric),
                sketch_regions=sketch,
                metric_regions=metric,
                source="manual",
            )
            description = f"Link sketch {_regions_text(sketch)} to metric {_regions_text(metric)}"
        else:
            old = self._corr.clique(into)
            new_sketch = tuple(region for region in sketch if region not in old.sketch_regions)
            new_metric = tuple(region for region in metric if region not in old.metric_regions)
            if not new_sketch and not new_metric:
                return old.id
            clique = dataclasses.replace(
                old,
                sketch_points=old.sketch_points + self._interior_points("sketch", new_sketch),
                metric_points=old.metric_points + self._interior_points("metric", new_metric),
                sketch_regions=old.sketch_regions + new_sketch,
                metric_regions=old.metric_regions + new_metric,
                source="manual",
            )
            description = f"Add regions to clique {old.id}"
        self._commit(description, self._corr.with_clique(clique))
        return clique.id

    def unlink(self, side: str, region: int) -> None:
        """Remove ``region`` and its points from every clique; delete cliques left empty.

        A point belongs to the region it falls in on the current segmentation (with the
        usual 10 px tolerance). A clique keeps living with one side empty (half-made
        cliques are normal while annotating) and is deleted only when both sides are.

        Raises
        ------
        ValueError
            ``side`` is not segmented (there is no way to tell which points are the region's).
        """
        _check_side(side)
        segmentation = self._segmentations[side]
        if segmentation is None:
            raise ValueError(f"the {side} map is not segmented")
        region = int(region)
        points_field, regions_field = f"{side}_points", f"{side}_regions"
        cliques = []
        for clique in self._corr.cliques:
            if region not in getattr(clique, regions_field):
                cliques.append(clique)
                continue
            points = getattr(clique, points_field)
            owners = regions_at_points(segmentation.labels, points, tolerance=REFERENCE_TOLERANCE)
            shrunk = dataclasses.replace(
                clique,
                **{
                    points_field: tuple(point for point, owner in zip(points, owners) if owner != region),
                    regions_field: tuple(r for r in getattr(clique, regions_field) if r != region),
                },
            )
            if not shrunk.is_empty:
                cliques.append(shrunk)
        self._commit(f"Unlink {side} region {region}", self._corr.with_cliques(cliques))

    def delete_clique(self, clique_id: int) -> None:
        """Delete a clique (KeyError when there is none)."""
        self._commit(f"Delete clique {clique_id}", self._corr.without_clique(clique_id))

    def set_status(self, clique_id: int, status: str) -> None:
        """Set a clique's review status: 'accepted', 'rejected' or 'pending'."""
        if status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {status!r}")
        clique = self._corr.clique(clique_id)
        self._commit(
            f"{_STATUS_VERBS[status]} clique {clique.id}",
            self._corr.with_clique(dataclasses.replace(clique, status=status)),
        )

    def set_note(self, clique_id: int, text: str) -> None:
        """Set a clique's free-text note."""
        clique = self._corr.clique(clique_id)
        self._commit(
            f"Edit note of clique {clique.id}",
            self._corr.with_clique(dataclasses.replace(clique, note=str(text))),
        )

    def apply_match(self, result) -> None:
        """Replace every automatic clique by one clique per pair of ``result`` (one undo step).

        Manual cliques are kept, and a pair they already contain is not added again. New
        cliques are ``source='auto'`` with status None (pending), anchored at the regions'
        interior points, scored with the matcher's ``c`` value of the pair when available.
        ``anchors`` and ``last_match`` are updated (they are not part of the undo history).

        Raises
        ------
        ValueError
            A map is not segmented, or ``result`` names a region the current segmentations
            do not have (a result computed before a re-segmentation).
        """
        for side in SIDES:
            if self._segmentations[side] is None:
                raise ValueError(f"the {side} map is not segmented")
        pairs = [(int(sketch), int(metric)) for sketch, metric in result.pairs]
        for sketch, metric in pairs:
            self._checked_regions("sketch", [sketch], stale_hint=True)
            self._checked_regions("metric", [metric], stale_hint=True)
        kept = [clique for clique in self._corr.cliques if clique.source != "auto"]
        covered = {pair for clique in kept for pair in product(clique.sketch_regions, clique.metric_regions)}
        new_pairs = [pair for pair in dict.fromkeys(pairs) if pair not in covered]
        cliques = from_pairs(
            new_pairs,
            sketch_points_of=lambda region: self._interior_points("sketch", (region,))[0],
            metric_points_of=lambda region: self._interior_points("metric", (region,))[0],
            source="auto",
            scores=[self._match_score(result, pair) for pair in new_pairs],
            first_id=self._corr.next_clique_id(),
        )
        self._last_match = result
        self._anchors = [(int(sketch), int(metric)) for sketch, metric in getattr(result, "anchors", [])]
        if not self._commit(f"Apply match ({len(new_pairs)} pairs)", self._corr.with_cliques([*kept, *cliques])):
            # The cliques are the same, but anchors and last_match are new: views still refresh.
            self.correspondences_changed.emit()

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
        selection_changed = False
        if self._selected_clique is not None and not any(c.id == self._selected_clique for c in new.cliques):
            self._selected_clique = None
            selection_changed = True
        self._evaluate()
        if selection_changed:
            self.selection_changed.emit()
        self._announce_value_change(was_dirty)

    def _announce_value_change(self, was_dirty: bool) -> None:
        self.correspondences_changed.emit()
        if self.dirty != was_dirty:
            self.dirty_changed.emit(self.dirty)

    def _clear_side_selection(self, side: str) -> bool:
        changed = bool(self._selection[side]) or self._selected_clique is not None
        self._selection = {**self._selection, side: frozenset()}
        self._selected_clique = None
        return changed

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

    def _match_score(self, result, pair: tuple[int, int]) -> float | None:
        # The matcher's c value of the pair (lower = more alike); None when unavailable.
        matrix = getattr(result, "c_matrix", None)
        sketch_ids = sorted(self._segmentations["sketch"].graph.nodes)
        metric_ids = sorted(self._segmentations["metric"].graph.nodes)
        if matrix is None or getattr(matrix, "shape", None) != (len(sketch_ids), len(metric_ids)):
            return None
        value = float(matrix[sketch_ids.index(pair[0]), metric_ids.index(pair[1])])
        return value if value == value and abs(value) != float("inf") else None

    def _with_regions_from_points(self, corr: Correspondences) -> Correspondences:
        for side in SIDES:
            segmentation = self._segmentations[side]
            if segmentation is not None:
                corr = _with_side_regions(corr, side, segmentation.labels)
        return corr

    def _recompute_reference(self) -> None:
        if self._reference_corr is None:
            self._reference = None
            return
        sets = []
        for clique in self._reference_corr.cliques:
            pair = []
            for side in SIDES:
                segmentation = self._segmentations[side]
                points = getattr(clique, f"{side}_points")
                if segmentation is not None and points:
                    found = regions_at_points(segmentation.labels, points, tolerance=REFERENCE_TOLERANCE)
                    pair.append(frozenset(region for region in found if region != 0))
                elif segmentation is not None:
                    pair.append(frozenset())
                else:
                    pair.append(frozenset(getattr(clique, f"{side}_regions")))
            sets.append((pair[0], pair[1]))
        self._reference = sets

    def _evaluate(self) -> None:
        if self._reference is None:
            self._evaluation = None
            self._clique_marks = {}
            return
        from ursim_core.evaluation.scoring import score_matches

        pairs, owners = [], []
        for clique in self._corr.cliques:
            if clique.effective_status == "rejected":
                continue
            for pair in product(sorted(set(clique.sketch_regions)), sorted(set(clique.metric_regions))):
                pairs.append(pair)
                owners.append(clique.id)
        score = score_matches(pairs, self._reference)
        marks: dict[int, str] = {}
        for owner, label in zip(owners, score.pair_labels):
            if label == "fp":
                marks[owner] = "fp"
            else:
                marks.setdefault(owner, "tp")
        self._evaluation = score
        self._clique_marks = marks

    def _install_document(self, corr: Correspondences, *, path: Path | None, saved: Correspondences | None) -> None:
        """Load the maps and segmentations ``corr`` names into temporaries, then swap them in."""
        maps, segmentations, warnings = {}, {}, []
        for side in SIDES:
            maps[side], segmentations[side] = self._load_side(side, getattr(corr, side), path, warnings)
        current = corr
        for side in SIDES:
            if segmentations[side] is not None:
                current = _with_side_regions(current, side, segmentations[side].labels)

        # Nothing below can fail: the session changes all at once or not at all.
        was_dirty = self.dirty
        old_path = self._path
        self._maps = maps
        self._segmentations = segmentations
        self._corr = current
        self._saved = saved
        self._path = path
        self._history.clear()
        self._selection = {side: frozenset() for side in SIDES}
        self._selected_clique = None
        self._last_match = None
        self._anchors = []
        self._recompute_reference()
        self._evaluate()
        for side in SIDES:
            self.map_changed.emit(side)
            self.segmentation_changed.emit(side)
        if path != old_path:
            self.path_changed.emit(path)
        self.selection_changed.emit()
        self._announce_value_change(was_dirty)
        self.history_changed.emit()
        for warning in warnings:
            self.error.emit(warning)

    @staticmethod
    def _load_side(side: str, ref: MapRef, document: Path | None, warnings: list[str]):
        """(map, segmentation) of one side of a document; raises UrsimError naming both files."""
        from ursim_core.io.maps import load_map
        from ursim_core.segmentation import SEGMENTERS, load_label_image, segment

        if ref.path is None:
            return None, None
        where = f" (the {side} map of {document.name})" if document is not None else f" (the {side} map)"
        try:
            map_ = load_map(ref.path)
            if ref.size is not None and tuple(ref.size) != tuple(map_.shape):
                raise _size_mismatch_error(ref, map_, side)
            if ref.labels_path is not None and ref.labels_path.is_file():
                segmentation = load_label_image(ref.labels_path, shape=map_.shape)
            elif ref.segmentation_method in SEGMENTERS:
                segmentation = segment(
                    map_, method=ref.segmentation_method, preset=None, params=ref.segmentation_params
                )
            else:
                segmentation = None
                if ref.labels_path is not None:
                    warnings.append(
                        f"{ref.labels_path}: label image not found and the {side} segmentation cannot be "
                        f"recomputed (method {ref.segmentation_method!r}); segment the {side} map again"
                    )
        except UrsimError as error:
            raise type(error)(f"{error.problem}{where}", path=error.path, field=error.field) from error
        if ref.sha256 is not None and map_.sha256 is not None and ref.sha256.lower() != map_.sha256.lower():
            warnings.append(
                f"{ref.path}: the {side} map changed since the correspondences were saved; "
                f"check that the points still fall in the right rooms"
            )
        return map_, segmentation


def _size_mismatch_error(ref: MapRef, map_, side: str) -> UrsimError:
    """The error for a map whose size differs from the size the document recorded."""
    from ursim_core.errors import MapError

    return MapError(
        f"is {map_.shape[0]}x{map_.shape[1]} (rows x cols) but the correspondences were made on a "
        f"{ref.size[0]}x{ref.size[1]} {side} map",
        path=ref.path,
    )
