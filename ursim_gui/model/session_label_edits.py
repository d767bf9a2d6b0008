"""Segmentation edits of :class:`~ursim_gui.model.session.AnnotationSession`: merge, split, walls.

A mixin. Each edit is one undo step: the new label image becomes the side's
segmentation (method ``edited``, its parameters naming the method it started from and an
edit counter), the side's map reference in the correspondences changes with it, and
every clique's regions on that side are re-derived from its points (the points stay
authoritative). Undo and redo swap the segmentation back with the reference: every
version of a side's labels is kept, keyed by its (method, parameters), while the
document is open. On save, an edited side's labels are written beside the file as
``<file stem>.<side>.labels.png`` and referenced in it, so reopening restores them exactly.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np

from ursim_gui.model import label_edits
from ursim_gui.model.session_values import SIDES, _check_side, _with_side_regions

__all__ = ["LabelEditOperations", "EDITED_METHOD", "labels_path_for"]

EDITED_METHOD = "edited"


def _key(ref) -> tuple[str | None, str]:
    return ref.segmentation_method, json.dumps(ref.segmentation_params, sort_keys=True, default=str)


def labels_path_for(document, side: str):
    """Where an edited side's label image goes when the document is saved to ``document``."""
    return document.with_name(f"{document.stem}.{side}.labels.png")


class LabelEditOperations:
    """Merge, split, paint and erase walls on a side's segmentation (one undo step each)."""

    def merge_regions(self, side: str, keep: int, merged) -> bool:
        """Region(s) ``merged`` (an id or ids) join region ``keep``, as one step. False when nothing changed."""
        labels = self._labels_to_edit(side)
        others = [int(merged)] if isinstance(merged, (int, np.integer)) else [int(r) for r in merged]
        for region in others:
            labels = label_edits.merge_regions(labels, int(keep), region)
        names = ", ".join(str(r) for r in [keep, *others])
        return self._edit_labels(side, labels, f"Merge {side} regions {names}")

    def split_region(self, side: str, region: int, start, end) -> bool:
        """Cut ``region`` along the line ``start`` -> ``end`` ((row, col) pixels)."""
        labels = self._labels_to_edit(side)
        return self._edit_labels(
            side, label_edits.split_region(labels, int(region), start, end), f"Split {side} region {region}"
        )

    def paint_wall(self, side: str, points, *, width: int = 3) -> bool:
        """Paint a wall stroke through ``points``; a region it cuts in two becomes two."""
        labels = self._labels_to_edit(side)
        return self._edit_labels(side, label_edits.paint_wall(labels, points, width=width), f"Paint a {side} wall")

    def erase_wall(self, side: str, points, *, width: int = 3) -> bool:
        """Erase a wall stroke: its wall pixels join the region around them."""
        labels = self._labels_to_edit(side)
        return self._edit_labels(side, label_edits.erase_wall(labels, points, width=width), f"Erase a {side} wall")

    # ---- internals ---------------------------------------------------------------------
    def _labels_to_edit(self, side: str) -> np.ndarray:
        segmentation = self._segmentations[_check_side(side)]
        if segmentation is None:
            raise ValueError(f"the {side} map is not segmented")
        return segmentation.labels

    def _edit_labels(self, side: str, labels: np.ndarray, description: str) -> bool:
        from ursim_core.segmentation import Segmentation
        from ursim_core.segmentation.graph import region_graph

        current = self._segmentations[side]
        if np.array_equal(labels, current.labels):
            return False
        old_ref = getattr(self._corr, side)
        self._label_versions[(side, _key(old_ref))] = current
        if old_ref.segmentation_method == EDITED_METHOD:
            origin = dict(old_ref.segmentation_params)
        else:
            origin = {"edited_from": old_ref.segmentation_method, "from_params": dict(old_ref.segmentation_params)}
        self._label_edit_count += 1
        params = {**origin, "edit": self._label_edit_count}
        labels = labels.astype(np.int32)
        edited = Segmentation(labels=labels, graph=region_graph(labels), method=EDITED_METHOD, params=params)
        new_ref = dataclasses.replace(
            old_ref, segmentation_method=EDITED_METHOD, segmentation_params=params, labels_path=None
        )
        self._label_versions[(side, _key(new_ref))] = edited
        self._segmentations[side] = edited
        self._clear_side_selection(side)
        self._recompute_reference()
        self._commit(description, _with_side_regions(dataclasses.replace(self._corr, **{side: new_ref}), side, labels))
        self.segmentation_changed.emit(side)
        self.selection_changed.emit()
        return True

    def _sync_segmentations(self) -> None:
        """After undo / redo: each side's segmentation is the version its map reference names."""
        for side in SIDES:
            ref = getattr(self._corr, side)
            version = self._label_versions.get((side, _key(ref)))
            if version is not None and version is not self._segmentations[side]:
                self._segmentations[side] = version
                self._clear_side_selection(side)
                self._recompute_reference()
                self.segmentation_changed.emit(side)

    def edited_labels_beside(self, corr, target):
        """``corr`` referencing copies of the edited sides' label images, written beside ``target``.

        For the autosave copy: the session and its history are not changed (a save does that,
        :meth:`_write_edited_labels`), so recovering the copy restores the edits too.
        """
        from ursim_core.segmentation import save_label_image

        for side in SIDES:
            ref = getattr(corr, side)
            if ref.segmentation_method != EDITED_METHOD or self._segmentations[side] is None:
                continue
            path = labels_path_for(target, side)
            save_label_image(self._segmentations[side], path)
            corr = dataclasses.replace(corr, **{side: dataclasses.replace(ref, labels_path=path)})
        return corr

    def _write_edited_labels(self, corr, target):
        """Save edited sides' label images beside ``target``; returns ``corr`` referencing them."""
        from ursim_core.segmentation import save_label_image

        for side in SIDES:
            ref = getattr(corr, side)
            if ref.segmentation_method != EDITED_METHOD or self._segmentations[side] is None:
                continue
            path = labels_path_for(target, side)
            save_label_image(self._segmentations[side], path)
            key = _key(ref)

            def with_path(value, side=side, key=key, path=path):
                other = getattr(value, side)
                return (
                    dataclasses.replace(value, **{side: dataclasses.replace(other, labels_path=path)})
                    if _key(other) == key
                    else value
                )

            self._history.map_values(with_path)
            corr = with_path(corr)
        return corr
