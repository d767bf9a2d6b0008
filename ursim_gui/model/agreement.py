"""Agreement between annotators, and of the matcher with each, per pair and for a whole campaign.

Qt-free. Annotator A is the campaign's own files, B a second annotator's (another
campaign's files, or a dataset's ground truth ``.dat``), the matcher is A's automatic
cliques (``source == "auto"``, whatever A decided about them). Every side's cliques are
turned into region sets through their *points* on one segmentation of each map (10 px
tolerance, as the evaluation), so the three are compared on the same regions:

- F1 of A against B (B as the reference), the usual pair F1 of
  :func:`ursim_core.evaluation.scoring.score_matches`; rejected cliques are no claim;
- F1 of the matcher against A and against B;
- F1 of the *ceiling* against A and against B: the one-to-one answer with the best mean F1
  against both at once (:func:`ursim_core.evaluation.ceiling.best_one_to_one`), what any
  one-to-one matcher can reach where A and B disagree;
- place accuracy of the same (:func:`ursim_core.evaluation.place.place_accuracy`;
  its reference metric segmentation is the pair's metric segmentation here).

The whole set pools TP / FP / FN over the pairs (a micro F1) and averages place accuracy
over the pairs that have one.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from itertools import product
from pathlib import Path

from ursim_core.correspondences import (
    Correspondences,
    load_correspondence_file,
    load_correspondences,
    regions_at_points,
)
from ursim_core.io.atomic import atomic_write_bytes

__all__ = [
    "COMPARISONS",
    "Agreement",
    "PairAgreement",
    "load_annotation",
    "region_sets",
    "pair_agreement",
    "pooled",
    "agreement_csv",
    "AgreementJob",
]

#: The comparisons, as (name, claimed by, reference).
COMPARISONS = (
    ("A vs B", "a", "b"),
    ("matcher vs A", "matcher", "a"),
    ("matcher vs B", "matcher", "b"),
    ("ceiling vs A", "ceiling", "a"),
    ("ceiling vs B", "ceiling", "b"),
)
_TOLERANCE = 10


@dataclass(frozen=True)
class Agreement:
    """One comparison: counts, F1 and place accuracy (None when not available)."""

    tp: int
    fp: int
    fn: int
    f1: float | None
    place: float | None = None


@dataclass(frozen=True)
class PairAgreement:
    """The comparisons of one pair; ``disagreeing`` = A's clique ids B does not share."""

    name: str
    comparisons: dict[str, Agreement]
    disagreeing: tuple[int, ...] = ()


def load_annotation(path: Path) -> Correspondences:
    """A correspondence JSON or a legacy ``.dat`` file."""
    return load_correspondence_file(path)


def region_sets(corr: Correspondences, sketch_labels, metric_labels, *, which: str = "claims"):
    """(clique id, sketch regions, metric regions) of the cliques, from their points.

    ``which``: "claims" = the non-rejected cliques, "matcher" = the automatic ones.
    """
    if which == "matcher":
        cliques = [clique for clique in corr.cliques if clique.source == "auto"]
    else:
        cliques = [clique for clique in corr.cliques if clique.effective_status != "rejected"]
    sets = []
    for clique in cliques:
        sides = []
        for labels, points in ((sketch_labels, clique.sketch_points), (metric_labels, clique.metric_points)):
            found = regions_at_points(labels, points, tolerance=_TOLERANCE) if points else []
            sides.append(frozenset(int(region) for region in found if region != 0))
        sets.append((clique.id, sides[0], sides[1]))
    return sets


def _compare(claimed, reference, *, place_inputs=None) -> Agreement:
    from ursim_core.evaluation.place import place_accuracy
    from ursim_core.evaluation.scoring import score_matches

    pairs = sorted({pair for _id, sketch, metric in claimed for pair in product(sketch, metric)})
    score = score_matches(pairs, [(sketch, metric) for _id, sketch, metric in reference])
    defined = (score.tp + score.fp) > 0 and (score.tp + score.fn) > 0
    place = None
    if place_inputs is not None:
        reference_corr, sketch_labels, metric_labels = place_inputs
        value = place_accuracy(pairs, reference_corr, sketch_labels, metric_labels, metric_labels).accuracy
        place = None if math.isnan(value) else float(value)
    return Agreement(score.tp, score.fp, score.fn, float(score.f1) if defined else None, place)


def pair_agreement(name: str, a: Correspondences, b: Correspondences, sketch_labels, metric_labels) -> PairAgreement:
    """The comparisons of one pair on the given segmentations."""
    from ursim_core.evaluation.ceiling import best_one_to_one

    sets = {
        "a": region_sets(a, sketch_labels, metric_labels),
        "b": region_sets(b, sketch_labels, metric_labels),
        "matcher": region_sets(a, sketch_labels, metric_labels, which="matcher"),
    }
    ceiling = best_one_to_one([[(sketch, metric) for _id, sketch, metric in sets[side]] for side in ("a", "b")])
    sets["ceiling"] = [(index, frozenset({s}), frozenset({m})) for index, (s, m) in enumerate(ceiling.pairs, 1)]
    values = {"a": a, "b": b}
    comparisons = {}
    for label, claimed, reference in COMPARISONS:
        reference_corr = values[reference].with_cliques(
            [c for c in values[reference].cliques if c.effective_status != "rejected"]
        )
        comparisons[label] = _compare(
            sets[claimed], sets[reference], place_inputs=(reference_corr, sketch_labels, metric_labels)
        )
    b_pairs = {pair for _id, sketch, metric in sets["b"] for pair in product(sketch, metric)}
    disagreeing = tuple(
        clique_id
        for clique_id, sketch, metric in sets["a"]
        if any(pair not in b_pairs for pair in product(sketch, metric))
    )
    return PairAgreement(name, comparisons, disagreeing)


def pooled(rows: list[PairAgreement]) -> dict[str, Agreement]:
    """Whole-set comparisons: TP / FP / FN summed (micro F1), place accuracy averaged over pairs."""
    result = {}
    for label, _claimed, _reference in COMPARISONS:
        parts = [row.comparisons[label] for row in rows if label in row.comparisons]
        tp, fp, fn = (sum(getattr(part, name) for part in parts) for name in ("tp", "fp", "fn"))
        f1 = 2 * tp / (2 * tp + fp + fn) if tp + fp > 0 and tp + fn > 0 else None
        places = [part.place for part in parts if part.place is not None]
        result[label] = Agreement(tp, fp, fn, f1, sum(places) / len(places) if places else None)
    return result


def agreement_csv(rows: list[PairAgreement], path: Path | None = None) -> str:
    """The table (one row per pair, then 'ALL'); written atomically to ``path`` when given."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    header = ["pair"]
    for label, _c, _r in COMPARISONS:
        key = label.replace(" ", "_")
        header += [f"{key}_tp", f"{key}_fp", f"{key}_fn", f"{key}_f1", f"{key}_place"]
    writer.writerow(header)

    def cells(comparisons):
        out = []
        for label, _c, _r in COMPARISONS:
            value = comparisons.get(label)
            if value is None:
                out += ["", "", "", "", ""]
                continue
            f1 = "" if value.f1 is None else f"{value.f1:.4f}"
            place = "" if value.place is None else f"{value.place:.4f}"
            out += [value.tp, value.fp, value.fn, f1, place]
        return out

    for row in rows:
        writer.writerow([row.name, *cells(row.comparisons)])
    writer.writerow(["ALL", *cells(pooled(rows))])
    text = buffer.getvalue()
    if path is not None:
        atomic_write_bytes(Path(path), text.encode("utf-8"))
    return text


class AgreementJob:
    """Agreement of every pair that has both files, for the worker process.

    Parameters
    ----------
    pairs : list of (name, sketch path, metric path, A file, B file)
    preset : dict, optional
        Segmentation presets per side used when A's file records no method.

    Each map is segmented as A's file records (method and parameters), the metric map
    once per distinct file and parameters.
    """

    description = "Agreement of the campaign"

    def __init__(self, pairs, presets: dict | None = None):
        self.pairs = [tuple(pair) for pair in pairs]
        self.presets = dict(presets or {"sketch": "sketch", "metric": "robot"})

    def run(self, progress, cancelled) -> list[PairAgreement]:
        from ursim_core.io.maps import load_map
        from ursim_core.segmentation import SEGMENTERS, segment
        from ursim_gui.model.jobs import JobCancelled

        cache: dict = {}

        def labels_of(side, path, ref):
            if ref.segmentation_method in SEGMENTERS:
                key = (str(path), ref.segmentation_method, repr(sorted(ref.segmentation_params.items())))
                method, preset, params = ref.segmentation_method, None, ref.segmentation_params
            else:
                key = (str(path), "maoris", self.presets[side])
                method, preset, params = "maoris", self.presets[side], None
            if key not in cache:
                cache[key] = segment(load_map(path), method=method, preset=preset, params=params).labels
            return cache[key]

        rows = []
        for index, (name, sketch, metric, a_file, b_file) in enumerate(self.pairs):
            if cancelled():
                raise JobCancelled()
            progress(index / max(1, len(self.pairs)), f"pair {name}")
            a, b = load_correspondences(a_file), load_annotation(b_file)
            rows.append(
                pair_agreement(name, a, b, labels_of("sketch", sketch, a.sketch), labels_of("metric", metric, a.metric))
            )
        progress(1.0, "")
        return rows
