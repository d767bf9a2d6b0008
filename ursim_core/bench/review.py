"""``ursim bench review``: edits an annotator needs, by review workflow, on KTH and Halmstad E5.

For every map pair and annotator, :func:`ursim_core.evaluation.review.simulate_review` counts the
rejections and links that turn the matcher's answer into the annotator's cliques, by hand and with
the pair matched again on the review (:mod:`ursim_core.matching.constraints`): the 18 KTH sketches
(planar matcher) and the Halmstad E5 robot maps (the overlay matcher, which two linked places lay).
Printed, never asserted: a figure of how much annotation work the matcher and re-matching save.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["bench_review", "bench_review_halmstad", "print_review"]


def _row(name: str, annotator: str, sketch, metric, reference, config) -> dict:
    from ursim_core.evaluation.review import WORKFLOWS, simulate_review

    row = {"sketch": name, "annotator": annotator, "cliques": sum(1 for s, m in reference if s and m)}
    for workflow in WORKFLOWS:
        outcome = simulate_review(sketch, metric, reference, workflow=workflow, config=config)
        row[workflow] = outcome.edits
        row[f"{workflow} rounds"] = outcome.rounds
        row[f"{workflow} finished"] = outcome.finished
    return row


def bench_review(root: Path, *, config=None) -> list[dict]:
    """One row per KTH sketch and annotator: ``sketch``, ``annotator``, ``cliques`` (the reference's
    cliques with both sides), and per workflow its edits, matching rounds and whether it finished."""
    from ursim_core.evaluation.kth_protocol import kth_pairs

    cases = kth_pairs(root)
    return [
        _row(name, annotator, sketch, cases.model, cases.reference(annotator, name), config)
        for name, sketch in cases.sketches.items()
        for annotator in sorted(cases.references)
    ]


def bench_review_halmstad(folder: Path) -> list[dict]:
    """The rows of :func:`bench_review` for a Halmstad layout folder (e.g. ``.../E5``): the input
    maps segmented in their canonical pose, both with the matching preset, as ``ursim evaluate``
    does, and matched with the automatic matcher told they are robot maps (the overlay)."""
    from ursim_core.correspondences import load_dat
    from ursim_core.evaluation.kth_protocol import reference_cliques
    from ursim_core.evaluation.layouts import discover
    from ursim_core.io.maps import load_map
    from ursim_core.matching import MATCH_PRESETS, MatchConfig
    from ursim_core.segmentation import segment, segment_canonical

    segmented: dict = {}

    def segmentation(path: Path, canonical: bool):
        if (path, canonical) not in segmented:
            the_map = load_map(path)
            if canonical:
                segmented[path, canonical] = segment_canonical(the_map.free, preset=MATCH_PRESETS["sketch"])
            else:
                segmented[path, canonical] = segment(the_map, preset=MATCH_PRESETS["metric"])
        return segmented[path, canonical]

    rows = []
    for experiment in discover(folder):
        sketch, metric = segmentation(experiment.sketch, True), segmentation(experiment.metric, False)
        config = MatchConfig(input_kind=experiment.input_kind)
        for annotator, path in experiment.ground_truth.items():
            reference = reference_cliques(sketch.labels, metric.labels, load_dat(path).cliques)
            rows.append(_row(experiment.name, annotator, sketch, metric, reference, config))
    return rows


def print_review(rows: list[dict]) -> None:
    """The per-pair table, the totals and the worst pair of each workflow."""
    from ursim_core.evaluation.review import WORKFLOWS

    header = ["sketch", "annotator", "cliques", *WORKFLOWS]
    print("  ".join(f"{name:>11}" for name in header))
    for row in rows:
        cells = [row["sketch"], row["annotator"], row["cliques"]]
        cells += [f"{row[w]}{'' if row[f'{w} finished'] else '*'}" for w in WORKFLOWS]
        print("  ".join(f"{cell!s:>11}" for cell in cells))
    if not rows:
        return
    totals = {w: sum(row[w] for row in rows) for w in WORKFLOWS}
    base = totals["by hand"]
    print(
        "total edits: "
        + ", ".join(
            f"{w} {totals[w]}" + (f" ({(totals[w] - base) / base:+.0%})" if base and w != "by hand" else "")
            for w in WORKFLOWS
        )
        + f" over {len(rows)} reviews of {sum(row['cliques'] for row in rows)} cliques"
    )
    for w in WORKFLOWS:
        worst = max(rows, key=lambda row: row[w])
        unfinished = sum(1 for row in rows if not row[f"{w} finished"])
        print(
            f"{w}: worst {worst['sketch']} ({worst['annotator']}) {worst[w]} edits; rounds of matching "
            f"{sum(row[f'{w} rounds'] for row in rows)}" + (f"; * {unfinished} not finished" if unfinished else "")
        )
