"""Document operations of :class:`~ursim_gui.model.session.AnnotationSession`: open, save, .dat, reference.

A mixin so the session stays one object for the views while its file handling reads on
its own. It uses the session's state and internals (``_corr``, ``_commit``...).
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterable
from pathlib import Path

from ursim_core.correspondences import (
    Correspondences,
    MapRef,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
)
from ursim_core.errors import UrsimError
from ursim_gui.model.session_values import AUTOSAVE_ORIGIN_KEY, SIDES, _absolute, _check_side, _with_side_regions

__all__ = ["DocumentOperations", "drawn_map_path_for", "write_map_png"]


def drawn_map_path_for(document: Path, side: str) -> Path:
    """Where a drawn ``side`` map goes when the document is saved to ``document``."""
    return document.with_name(f"{document.stem}.{side}.png")


def write_map_png(map_, path: Path) -> str:
    """Write ``map_``'s grey image (its free space white when it has none) as a PNG, atomically;
    returns the file's SHA-256, as :func:`ursim_core.io.maps.load_map` records it."""
    import hashlib

    import cv2
    import numpy as np

    from ursim_core.io.atomic import atomic_write_bytes

    grey = map_.image if map_.image is not None else np.where(map_.free, 255, 0).astype(np.uint8)
    ok, encoded = cv2.imencode(".png", np.ascontiguousarray(grey))
    if not ok:
        raise OSError(f"{path}: could not encode the {map_.name} map as PNG")
    data = encoded.tobytes()
    atomic_write_bytes(path, data)
    return hashlib.sha256(data).hexdigest()


class DocumentOperations:
    """Open, restore, save, import/export ``.dat`` and the reference of a session."""

    # ------------------------------------------------------------------ documents
    def is_document_map(self, side: str, path: str | os.PathLike) -> bool:
        """True when ``path`` is the ``side`` map the document names, or it names none yet.

        Opening any other map starts a new document (:meth:`new_document`): the cliques,
        the reference and the file all belong to the old pair.
        """
        recorded = getattr(self._corr, _check_side(side)).path
        return recorded is None or Path(recorded) == _absolute(path)

    def new_document(self, *, keep: Iterable[str] = ()) -> None:
        """Start an untitled, empty document; the maps (and segmentations) of ``keep`` stay.

        The history, reference, selection and last match are cleared. Not undoable (like
        opening a file): callers ask about unsaved changes first.
        """
        keep = {_check_side(side) for side in keep}
        corr = Correspondences(annotator=self.annotator or self._corr.annotator)
        for side in keep:
            corr = dataclasses.replace(corr, **{side: getattr(self._corr, side)})
        was_dirty = self.dirty
        old_path = self._path
        for side in SIDES:
            if side not in keep:
                self._maps[side] = None
                self._segmentations[side] = None
        self._corr = corr
        self._saved = corr
        self._path = None
        self._history.clear()
        self._selection = {side: frozenset() for side in SIDES}
        self._selected_clique = None
        self._focus = None
        self._label_versions = {}
        self._forget_match()
        self._reference_corr = None
        self._reference_path = None
        self._recompute_reference()
        self._evaluate()
        for side in SIDES:
            if side not in keep:
                self.map_changed.emit(side)
                self.segmentation_changed.emit(side)
        if old_path is not None:
            self.path_changed.emit(None)
        self.selection_changed.emit()
        self.reference_changed.emit()
        self._announce_value_change(was_dirty)
        self.history_changed.emit()

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

    def restore(
        self,
        corr: Correspondences,
        *,
        origin: str | os.PathLike | None = None,
        autosave: str | os.PathLike | None = None,
    ) -> list[Path]:
        """Replace the document by a recovered value (from :func:`ursim_gui.model.autosave.recover`).

        The maps it names are loaded as in :meth:`open`. The document it belongs to is
        ``origin``, or the path the autosave file recorded under ``"autosave_of"`` (that key
        is removed so it never reaches the real file). The result is dirty: it has not been
        saved, unless it equals what the original file holds.

        ``autosave``: the copy ``corr`` was read from. A sketch drawn in the app and never saved
        was recovered from the copy's PNG beside it: it is a drawing again (no file), so a save
        writes it beside the document instead of naming a file in the autosave folder.

        Returns
        -------
        list of Path
            The copy's drawn-map files the session no longer needs (the caller deletes them
            with the copy).

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
        return [] if autosave is None else self._drawings_again(_absolute(autosave))

    def _drawings_again(self, autosave: Path) -> list[Path]:
        released = []
        for side in SIDES:
            map_, copy = self._maps[side], drawn_map_path_for(autosave, side)
            if map_ is None or map_.path is None or _absolute(map_.path) != copy:
                continue
            ref = getattr(self._corr, side)
            # No map_changed: the pixels are the same (as _adopt_drawn_file); titles follow path_changed.
            self._maps[side] = dataclasses.replace(map_, path=None, sha256=None)
            self._corr = dataclasses.replace(self._corr, **{side: dataclasses.replace(ref, path=None, sha256=None)})
            released.append(copy)
        if released:
            was_dirty = self.dirty
            self.path_changed.emit(self._path)
            self._announce_value_change(was_dirty)
        return released

    def save(self, path: str | os.PathLike | None = None, *, overwrite_changed: bool = False) -> None:
        """Write the correspondences to ``path`` (default: the current file), atomically.

        ``created`` (when empty) and ``modified`` are stamped. On success the document is
        clean and ``path`` becomes the current file. Saving to the current file checks that it
        is still what this session read or last wrote (SHA-256); ``overwrite_changed`` skips
        that check (the user chose to overwrite).

        Raises
        ------
        ValueError
            No ``path`` and the document has never been saved.
        ursim_core.errors.FileChangedError
            The current file changed on disk since this session read or wrote it (another
            session saved it): nothing is written.
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
        # A map drawn in the app has no file: it is written beside the document, or reopening
        # the document would give its cliques without their sketch.
        stamped, drawn = self.drawn_maps_beside(stamped, target)
        # An edited segmentation is saved beside the file and referenced in it.
        stamped = self._write_edited_labels(stamped, target)
        same_file = self._path is not None and target == self._path
        expected = getattr(self, "_disk_sha256", None) if same_file and not overwrite_changed else None
        self._disk_sha256 = save_correspondences(stamped, target, now=moment, expected_sha256=expected)
        for side, map_ in drawn.items():
            self._adopt_drawn_file(side, map_)

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

    def file_is_current(self) -> bool:
        """True when the document has a file and it holds what this session last read or wrote
        there (its SHA-256), and the document has no unsaved changes: saving would change nothing."""
        from ursim_core.correspondences.files import sha256_of_file

        if self._path is None or self.dirty:
            return False
        expected = getattr(self, "_disk_sha256", None)
        return expected is not None and sha256_of_file(self._path) == expected

    def drawn_maps_beside(self, corr: Correspondences, target: Path) -> tuple[Correspondences, dict]:
        """``corr`` referencing PNG files, written beside ``target``, of the maps that have none.

        A sketch drawn in the app (:mod:`ursim_gui.tools.sketch_canvas`) has no file until the
        document is saved: it goes to ``<target stem>.<side>.png``, whose grey image loads back
        as the same map. Returns the new value and ``{side: map with its new file}``; the
        session itself is not changed (:meth:`save` adopts the files once the document is
        written; the autosave copy only references them).
        """
        drawn = {}
        # The autosave calls this at each flush; a drawing does not change once shown, so its PNG
        # is encoded and written once per file (a KTH-sized one takes about 10 ms on the GUI thread).
        written = self._drawn_files
        for side in SIDES:
            map_ = self._maps[side]
            if map_ is None or map_.path is not None:
                continue
            path = drawn_map_path_for(target, side)
            kept = written.get(path)
            if kept is not None and kept[0] is map_ and path.is_file():
                sha256 = kept[1]
            else:
                sha256 = write_map_png(map_, path)
                written[path] = (map_, sha256)
            drawn[side] = dataclasses.replace(map_, path=path, sha256=sha256)
            ref = getattr(corr, side)
            if ref.path is None:
                corr = dataclasses.replace(corr, **{side: dataclasses.replace(ref, path=path, sha256=sha256)})
        return corr, drawn

    def _adopt_drawn_file(self, side: str, map_) -> None:
        """The drawn map of ``side`` now has the file ``map_.path``: the map and every value of
        the history name it, so the saved value and the current one agree."""

        def with_file(value: Correspondences) -> Correspondences:
            ref = getattr(value, side)
            if ref.path is not None:
                return value
            return dataclasses.replace(value, **{side: dataclasses.replace(ref, path=map_.path, sha256=map_.sha256)})

        # No map_changed: the pixels are the same, and a changed map would reset what the views
        # and the matching settings hold for it. The window's titles follow path_changed.
        self._maps[side] = map_
        self._history.map_values(with_file)
        self._corr = with_file(self._corr)

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
        """Write the cliques' points in the original ``.dat`` format (atomically).

        Rejected cliques are left out: the format has no status, and a reader would take
        every clique it holds for a correspondence.
        """
        kept = [clique for clique in self._corr.cliques if clique.effective_status != "rejected"]
        save_dat(self._corr.with_cliques(kept), _absolute(path))

    def _install_document(self, corr: Correspondences, *, path: Path | None, saved: Correspondences | None) -> None:
        """Load the maps and segmentations ``corr`` names into temporaries, then swap them in."""
        maps, segmentations, warnings = {}, {}, []
        for side in SIDES:
            maps[side], segmentations[side] = self._load_side(
                side, getattr(corr, side), path, warnings, read=self.read_ahead.read
            )
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
        # What this session last read from or wrote to ``path``: a save checks the file is unchanged.
        self._disk_sha256 = getattr(saved, "loaded_sha256", None)
        self._history.clear()
        self._selection = {side: frozenset() for side in SIDES}
        self._selected_clique = None
        self._focus = None
        self._label_versions = {}
        self._last_match = None
        self._laid = None
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
        self.document_opened.emit(current)
        for warning in warnings:
            self.error.emit(warning)

    @staticmethod
    def _load_side(side: str, ref: MapRef, document: Path | None, warnings: list[str], *, read=None):
        """(map, segmentation) of one side of a document; raises UrsimError naming both files.
        ``read(path) -> Map`` reads the map file (:func:`~ursim_core.io.maps.load_map` by default)."""
        from ursim_core.io.maps import load_map
        from ursim_core.segmentation import SEGMENTERS, load_label_image, segment, with_resamplings

        if ref.path is None:
            return None, None
        where = f" (the {side} map of {document.name})" if document is not None else f" (the {side} map)"
        try:
            map_ = (read or load_map)(ref.path)
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
        if side == "sketch" and segmentation is not None and ref.segmentation_method in SEGMENTERS:
            # A turned sketch was segmented in several resamplings, which the planar matcher votes
            # over; a saved document keeps the first only: make the others again, or matching the
            # reopened document would answer otherwise than before it was saved.
            try:
                segmentation = with_resamplings(
                    segmentation, map_, method=ref.segmentation_method, params=ref.segmentation_params
                )
            except UrsimError as error:
                why = f"{error.field}: {error.problem}" if error.field else error.problem
                warnings.append(
                    f"{ref.path}: the sketch's other resamplings could not be made ({why}); "
                    f"matching uses its one segmentation"
                )
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
