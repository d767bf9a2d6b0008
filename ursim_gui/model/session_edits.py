"""Undoable edits of :class:`~ursim_gui.model.session.AnnotationSession`: link, unlink, status, match.

A mixin: each method builds the new correspondence value and records it with the
session's ``_commit`` (exactly one history entry, none when nothing changes).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

from ursim_core.correspondences import STATUSES, Clique, from_pairs, regions_at_points
from ursim_core.matching.constraints import pairs_beside_review
from ursim_gui.model.session_values import REFERENCE_TOLERANCE, SIDES, _check_side, _regions_text
from ursim_gui.model.wording import counted

__all__ = ["EditOperations"]

_STATUS_VERBS = {"accepted": "Accept", "rejected": "Reject", "pending": "Mark pending"}
# apply_match without a laid sketch: the session makes it when a view asks (None is a laid sketch: none).
_NOT_GIVEN = object()


class EditOperations:
    """Link, unlink, delete, status, note and apply-match edits of a session."""

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

    def unlink(self, side: str, region: int, *, clique: int | None = None) -> None:
        """Remove ``region`` and its points from clique ``clique`` (default: from every clique).

        One undo step. See :meth:`unlink_regions`.
        """
        self.unlink_regions({side: [region]}, clique=clique)

    def unlink_regions(self, regions: dict, *, clique: int | None = None) -> None:
        """Remove regions (``{side: ids}``) and their points from cliques, as one undo step.

        With ``clique`` only that clique's membership changes; otherwise every clique
        that holds a region loses it. A point belongs to the region it falls in on the
        current segmentation (with the usual 10 px tolerance). A clique keeps living with
        one side empty (half-made cliques are normal while annotating) and is deleted
        only when both sides are.

        Raises
        ------
        ValueError
            A side with regions is not segmented (there is no way to tell which points
            are the region's).
        KeyError
            ``clique`` is not a clique id.
        """
        chosen = {_check_side(side): {int(r) for r in ids} for side, ids in regions.items() if ids}
        for side in chosen:
            if self._segmentations[side] is None:
                raise ValueError(f"the {side} map is not segmented")
        if clique is not None:
            self._corr.clique(clique)  # KeyError for an unknown id
        cliques = []
        for current in self._corr.cliques:
            if clique is not None and current.id != clique:
                cliques.append(current)
                continue
            for side, removed in chosen.items():
                points_field, regions_field = f"{side}_points", f"{side}_regions"
                if not removed & set(getattr(current, regions_field)):
                    continue
                points = getattr(current, points_field)
                owners = regions_at_points(self._segmentations[side].labels, points, tolerance=REFERENCE_TOLERANCE)
                current = dataclasses.replace(
                    current,
                    **{
                        points_field: tuple(point for point, owner in zip(points, owners) if owner not in removed),
                        regions_field: tuple(r for r in getattr(current, regions_field) if r not in removed),
                    },
                )
            if not current.is_empty:
                cliques.append(current)
        names = [f"{side} region {_regions_text(sorted(ids))}" for side, ids in chosen.items()]
        where = f" from clique {clique}" if clique is not None else ""
        self._commit(f"Unlink {' and '.join(names)}{where}", self._corr.with_cliques(cliques))

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

    def set_statuses(self, clique_ids: Iterable[int], status: str) -> None:
        """Set the review status of several cliques as one undo step (e.g. accept all)."""
        if status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {status!r}")
        ids = set(int(i) for i in clique_ids)
        cliques = [
            dataclasses.replace(clique, status=status) if clique.id in ids else clique for clique in self._corr.cliques
        ]
        self._commit(f"{_STATUS_VERBS[status]} {counted(len(ids), 'clique')}", self._corr.with_cliques(cliques))

    def relink(self, clique_id: int, side: str, regions: Iterable[int]) -> None:
        """Replace one side of a clique by ``regions`` (one undo step): fixes a wrong match.

        The clique turns manual and accepted: a person has just said which regions
        correspond. Its other side is untouched.

        Raises
        ------
        ValueError
            No region given, or one not in the current segmentation.
        KeyError
            ``clique_id`` is not a clique id.
        """
        _check_side(side)
        chosen = self._checked_regions(side, regions)
        if not chosen:
            raise ValueError("relink needs at least one region")
        clique = self._corr.clique(clique_id)
        fixed = dataclasses.replace(
            clique,
            **{f"{side}_points": self._interior_points(side, chosen), f"{side}_regions": chosen},
            source="manual",
            status="accepted",
        )
        self._commit(f"Relink clique {clique.id} to {side} {_regions_text(chosen)}", self._corr.with_clique(fixed))

    def set_note(self, clique_id: int, text: str) -> None:
        """Set a clique's free-text note."""
        clique = self._corr.clique(clique_id)
        self._commit(
            f"Edit note of clique {clique.id}",
            self._corr.with_clique(dataclasses.replace(clique, note=str(text))),
        )

    def set_label(self, clique_id: int, label: str | None) -> None:
        """Set a clique's semantic label (room name / type; blank removes it), one undo step.

        Saved in the clique's JSON as ``label`` and carried into the GeoJSON / labelme / QGIS exports.
        """
        from ursim_core.correspondences.exporters import clique_label, with_clique_label

        clique = self._corr.clique(clique_id)
        text = (label or "").strip() or None
        if text == clique_label(clique):
            return
        self._commit(f"Label clique {clique.id}", self._corr.with_clique(with_clique_label(clique, text)))

    def review_constraints(self):
        """What the person has reviewed so far, as constraints on the next match.

        Manual and accepted cliques become pairs every answer contains, rejected ones pairs no
        answer proposes again (:func:`ursim_core.matching.constraints_from_cliques`); pending
        automatic cliques say nothing. Cliques naming a region the current segmentations do not
        have are left out. None when there is nothing reviewed or a map is not segmented.
        """
        from ursim_core.matching import constraints_from_cliques

        if any(self._segmentations[side] is None for side in SIDES):
            return None
        graphs = {side: self._segmentations[side].graph for side in SIDES}
        sketch_regions, metric_regions = set(graphs["sketch"].nodes), set(graphs["metric"].nodes)
        reviewed = [
            clique
            for clique in self._corr.cliques
            if clique.is_reviewed
            and set(clique.sketch_regions) <= sketch_regions
            and set(clique.metric_regions) <= metric_regions
        ]
        constraints = constraints_from_cliques(
            reviewed, sizes={side: dict(graph.nodes(data="size", default=0)) for side, graph in graphs.items()}
        )
        return constraints or None

    def apply_match(self, result, *, laid=_NOT_GIVEN) -> None:
        """Replace the pending automatic cliques by one clique per new pair of ``result`` (one undo step).

        Every clique a person made or reviewed is kept: manual, accepted and rejected ones. A
        pair is not added when a kept clique already holds one of its regions (a region a
        person vouched for gets no second, automatic partner) or when a rejected clique holds
        the pair. New cliques are ``source='auto'`` with status None (pending), anchored at the
        regions' interior points, scored with the matcher's ``c`` value of the pair when
        available. The file's ``matcher`` record says what produced them
        (:func:`ursim_core.matching.results.match_record`). ``anchors`` and ``last_match`` are
        updated (they are not part of the undo history). ``laid``: the result's laid sketch, made
        with the current segmentations (:meth:`laid_sketch` then returns it without computing).

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
        kept = [clique for clique in self._corr.cliques if clique.is_reviewed]
        new_pairs = pairs_beside_review(pairs, kept)
        cliques = from_pairs(
            new_pairs,
            sketch_points_of=lambda region: self._interior_points("sketch", (region,))[0],
            metric_points_of=lambda region: self._interior_points("metric", (region,))[0],
            source="auto",
            scores=[self._match_score(result, pair) for pair in new_pairs],
            first_id=self._corr.next_clique_id(),
        )
        self._last_match = result
        self._laid = None
        if laid is not _NOT_GIVEN:
            made_of = (result, self._segmentations["sketch"].labels, self._segmentations["metric"].labels)
            self._laid = (made_of, laid)
        self._anchors = [(int(sketch), int(metric)) for sketch, metric in getattr(result, "anchors", [])]
        value = self._corr.with_cliques([*kept, *cliques])
        if getattr(result, "config", None) is not None:
            from ursim_core.matching.results import match_record

            # What produced the automatic cliques, as ``ursim match`` writes it: the file says how
            # the sketch was read when it is opened again.
            value = dataclasses.replace(value, extra={**value.extra, "matcher": match_record(result.config, result)})
        if not self._commit(f"Apply match ({len(new_pairs)} pairs)", value):
            # The cliques are the same, but anchors and last_match are new: views still refresh.
            self.correspondences_changed.emit()

    def _match_score(self, result, pair: tuple[int, int]) -> float | None:
        # The matcher's c value of the pair (lower = more alike); None when unavailable.
        matrix = getattr(result, "c_matrix", None)
        sketch_ids = sorted(self._segmentations["sketch"].graph.nodes)
        metric_ids = sorted(self._segmentations["metric"].graph.nodes)
        if matrix is None or getattr(matrix, "shape", None) != (len(sketch_ids), len(metric_ids)):
            return None
        value = float(matrix[sketch_ids.index(pair[0]), metric_ids.index(pair[1])])
        return value if value == value and abs(value) != float("inf") else None
