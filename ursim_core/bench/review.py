"""``ursim bench review``: edits an annotator needs on the KTH sketches, by review workflow.

For every sketch and annotator, :func:`ursim_core.evaluation.review.simulate_review` counts the
rejections and links that turn the matcher's answer into the annotator's cliques, by hand and with
the pair matched again on the review (:mod:`ursim_core.matching.constraints`). Printed, never
asserted: a figure of how much annotation work the matcher and re-matching save.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["bench_review", "print_review"]


def bench_review(root: Path, *, config=None) -> list[dict]:
    """One row per sketch and annotator: ``sketch``, ``annotator``, ``cliques`` (the reference's
    cliques with both sides), and per workflow its edits and whether it finished."""
    from ursim_core.evaluation.kth_protocol import kth_pairs
    from ursim_core.evaluation.review import WORKFLOWS, simulate_review

    cases = kth_pairs(root)
    rows = []
    for name, sketch in cases.sketches.items():
        for annotator in sorted(cases.references):
            reference = cases.reference(annotator, name)
            row = {"sketch": name, "annotator": annotator, "cliques": sum(1 for s, m in reference if s and m)}
            for workflow in WORKFLOWS:
                outcome = simulate_review(sketch, cases.model, reference, workflow=workflow, config=config)
                row[workflow] = outcome.edits
                row[f"{workflow} rounds"] = outcome.rounds
                row[f"{workflow} finished"] = outcome.finished
            rows.append(row)
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
