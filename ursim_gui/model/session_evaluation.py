"""Evaluation of :class:`~ursim_gui.model.session.AnnotationSession` against a reference.

A mixin: the reference cliques, their regions on the current segmentations, the score of
the non-rejected cliques and the per-clique TP/FP marks the views draw.
"""

from __future__ import annotations

import os
from itertools import product

from ursim_core.correspondences import load_correspondence_file, regions_at_points
from ursim_gui.model.session_values import REFERENCE_TOLERANCE, SIDES, _absolute

__all__ = ["EvaluationOperations"]


class EvaluationOperations:
    """Reference loading, scoring and the evaluation queries of a session."""

    def load_reference(self, path: str | os.PathLike) -> None:
        """Load reference cliques (``.json`` or ``.dat``) to evaluate the correspondences against.

        Reference regions come from the reference's points on the current segmentations
        (tolerance 10 px, as the released evaluation), or from the file's region ids on a
        side that is not segmented.
        """
        path = _absolute(path)
        reference = load_correspondence_file(path)
        self._reference_corr = reference
        self._reference_path = path
        self._recompute_reference()
        self._evaluate()
        self.reference_changed.emit()

    def clear_reference(self) -> None:
        """Stop evaluating."""
        if self._reference_corr is None:
            return
        self._reference_corr = None
        self._reference_path = None
        self._recompute_reference()
        self._evaluate()
        self.reference_changed.emit()

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

    def _recompute_reference(self) -> None:
        if self._reference_corr is None:
            self._reference = None
            return
        sets = []
        # A rejected clique is no correspondence: it cannot be found or missed.
        for clique in (c for c in self._reference_corr.cliques if c.effective_status != "rejected"):
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
        self._place = None
        if self._reference is None:
            self._evaluation = None
            self._clique_marks = {}
            return
        from ursim_core.evaluation.place import place_accuracy
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
        sketch, metric = self._segmentations["sketch"], self._segmentations["metric"]
        if sketch is not None and metric is not None and self._reference_corr is not None:
            # Places are read in the session's own metric segmentation (the GUI segments metric
            # maps with MAORIS 'default', the reference segmentation of the definition).
            kept = [c for c in self._reference_corr.cliques if c.effective_status != "rejected"]
            self._place = place_accuracy(pairs, kept, sketch.labels, metric.labels, metric.labels, metric.graph)

    @property
    def place(self):
        """``ursim_core.evaluation.place.PlaceScore`` of the non-rejected cliques, or None."""
        return getattr(self, "_place", None)
