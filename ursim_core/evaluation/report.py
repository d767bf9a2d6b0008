"""Reports of an evaluation: Table-1-style text, runs.csv, plots and a markdown summary.

Everything here is a pure function of an :class:`ursim_core.evaluation.results.EvaluationResult`
(its ``rows``, ``human_rows``, ``summaries``, ``settings`` and ``timings``), except
:func:`write_report`, which writes the files atomically. The text tables are
:mod:`~ursim_core.evaluation.tables`, the plots :mod:`~ursim_core.evaluation.plots`, the published
figures quoted for comparison :mod:`~ursim_core.evaluation.published`.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ursim_core.evaluation.formatting import MATCHER_NAMES, VARIANT_NAMES, markdown_table, number
from ursim_core.evaluation.plots import plot_boxplots, plot_f1_vs_m, plot_place_vs_m
from ursim_core.evaluation.published import published_markdown
from ursim_core.evaluation.results import POOLED, RUN_COLUMNS, mean_f1_by_m
from ursim_core.evaluation.tables import (
    CHOICE_TITLES,
    annotator_groups,
    ceiling_lines,
    format_tables,
    heading,
    headline_choice,
    human_lines,
    methods,
    orientation_table,
    per_sketch_table,
    table1,
)

__all__ = ["runs_csv", "format_tables", "markdown_summary", "plot_f1_vs_m", "plot_boxplots", "write_report"]


# --------------------------------------------------------------------------- CSV


def runs_csv(result) -> str:
    """Every run (matcher rows, then human-vs-human rows, then the ceiling's) as CSV text, one row per RunRow.

    Floats are written with 6 significant digits; a NaN (the m of a human row, a place accuracy
    with no scorable clique) is empty.

    Examples
    --------
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> row = RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 1, 0, 0.5, 1.0, 2 / 3, 4, 5, 6, 0.01)
    >>> runs_csv(EvaluationResult(rows=(row,))).splitlines()[1]
    '00,a,planar,T4,0.1,0.1,1,1,0,0.5,1,0.666667,4,5,6,0.01,,0,correct,,,'
    """

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(RUN_COLUMNS)
    for row in (*result.rows, *result.human_rows, *result.ceiling_rows):
        writer.writerow([_csv_value(getattr(row, column)) for column in RUN_COLUMNS])
    return buffer.getvalue()


def _csv_value(value: Any) -> Any:
    if isinstance(value, float):
        return "" if math.isnan(value) else format(value, ".6g")
    return value


# --------------------------------------------------------------------------- markdown


def markdown_summary(
    result, *, files: Sequence[str] = ("runs.csv", "f1_vs_m.png", "place_vs_m.png", "boxplots.png")
) -> str:
    """The summary.md text: settings, Table-1-style tables, F1 per m, published figures, notes.

    Examples
    --------
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, 1.0, 1, 3, 3, 0.0)]
    >>> "| Planar median | 1.00 |" in markdown_summary(EvaluationResult(rows=tuple(rows)))
    True
    """

    settings = result.settings
    lines = ["# URSIM evaluation", ""]
    lines += [f"- {line}" for line in heading(result)]
    config = settings.get("config")
    if config:
        lines.append("- matching configuration: " + ", ".join(f"`{k}={v}`" for k, v in config.items() if k != "m_grid"))
    lines.append("- files: " + ", ".join(f"[{name}]({name})" for name in files))
    lines.append("")
    lines += [
        "F1 per map pair, then median and mean ± sample sd over the maps. *Oracle* picks the best m of the grid",
        "for each map (as the paper's Table 1), *best fixed m* the single m with the highest mean F1, *automatic m*",
        "the matcher's own choice. Ground-truth points are mapped onto the evaluated segmentation (10 px tolerance).",
        "*Place* rows: mean place accuracy (would a robot sent to each sketched ground-truth point reach the",
        "annotated place? Points with no region or an unmatched region fail; mean over a clique's points, then",
        f"over cliques; places in the MAORIS `{settings.get('place_reference_preset', 'default')}` segmentation of the metric map).",
        "",
    ]
    for annotator in annotator_groups(result):
        who = (
            "all annotators pooled (one sample per map and annotator)"
            if annotator == POOLED
            else f"annotator {annotator}"
        )
        lines += [f"## {who}", ""]
        for choice in ("oracle", "fixed", "auto"):
            header, rows, n_maps = table1(result, annotator, choice)
            if not n_maps:
                continue
            lines += [f"### F1, {CHOICE_TITLES[choice]} ({n_maps} maps)", "", markdown_table(header, rows), ""]
        precision_rows = _precision_recall_rows(result, annotator)
        if precision_rows:
            lines += [
                "### Mean precision / recall at the oracle m",
                "",
                markdown_table(["matcher", *_variant_header(result)], precision_rows),
                "",
            ]

    human = human_lines(result)
    if human:
        lines += ["## Human vs human", ""] + [f"- {line}" for line in human] + [""]
    ceiling = ceiling_lines(result)
    if ceiling:
        lines += (
            [
                "## Ceiling of a one-to-one matcher",
                "",
                "A matcher gives one answer per map pair, scored against every annotator. Where the annotators",
                "disagree, or a clique joins several regions on a side, no one-to-one answer scores 1 against all of",
                "them: the ceiling is the best mean F1 any one-to-one answer reaches (its pairs found by exhaustive",
                "search, then scored as a matcher's), and the place accuracy of that answer.",
                "",
            ]
            + [f"- {line}" for line in ceiling]
            + [""]
        )

    table = orientation_table(result)
    if table is not None:
        lines += [
            f"## Per orientation ({CHOICE_TITLES[headline_choice(result)]}, all annotators pooled)",
            "",
            "Mean F1 / mean place accuracy of the sketches turned and mirrored (mirror first, then turned",
            "counter-clockwise; ground truth transformed alike). *worst*: the lowest F1 of each column.",
            "",
            markdown_table(*table),
            "",
        ]

    by_m = mean_f1_by_m(result.rows)
    if by_m:
        lines += ["## Mean F1 for each fixed m", ""]
        lines += _by_m_tables(by_m)

    by_m = mean_f1_by_m(result.rows, value="place_accuracy")
    if by_m:
        lines += ["## Mean place accuracy for each fixed m", ""]
        lines += _by_m_tables(by_m)

    lines += _per_sketch_markdown(result)

    lines += ["## Published figures for comparison", ""]
    lines += published_markdown(result)
    if result.notes:
        lines += ["## Notes", ""] + [f"- {note}" for note in result.notes] + [""]
    reasons = _reason_counts(result)
    if reasons:
        lines += ["## Degenerate runs (reason reported by the matcher, count of runs)", ""]
        lines += [f"- {count} x {reason}" for reason, count in reasons] + [""]
    return "\n".join(lines).rstrip() + "\n"


def _by_m_tables(by_m) -> list[str]:
    lines = []
    annotators = list(dict.fromkeys(key[0] for key in by_m))
    for annotator in annotators:
        keys = [key for key in by_m if key[0] == annotator]
        labels = sorted({(m, label) for key in keys for m, label, _, _ in by_m[key]})
        header = ["m"] + [f"{MATCHER_NAMES.get(k[1], k[1])} {VARIANT_NAMES.get(k[2], k[2])}" for k in keys]
        values = {key: {lab: mean for _, lab, mean, _ in by_m[key]} for key in keys}
        table_rows = [[label] + [number(values[key].get(label, math.nan)) for key in keys] for _, label in labels]
        lines += [f"### {annotator}", "", markdown_table(header, table_rows), ""]
    return lines


def _per_sketch_markdown(result) -> list[str]:
    matchers, variants = methods(result)
    choice = headline_choice(result)
    sections = []
    for matcher in matchers:
        for variant in variants:
            table = per_sketch_table(result, matcher, variant, choice)
            if table is not None and table[1]:
                title = f"{MATCHER_NAMES.get(matcher, matcher)} {VARIANT_NAMES.get(variant, variant)}"
                sections += [f"### {title}", "", markdown_table(*table), ""]
    if not sections:
        return []
    return [
        f"## Per sketch ({CHOICE_TITLES[choice]}): F1 / place accuracy, mean over the annotators",
        "",
        *sections,
    ]


def _variant_header(result) -> list[str]:
    return [VARIANT_NAMES.get(v, v) for v in methods(result)[1]]


def _precision_recall_rows(result, annotator: str) -> list[list[str]]:
    matchers, variants = methods(result)
    rows = []
    for matcher in matchers:
        cells = []
        for variant in variants:
            item = result.summary(annotator, matcher, variant, "oracle")
            cells.append("-" if item is None else f"{number(item.mean_precision)} / {number(item.mean_recall)}")
        rows.append([MATCHER_NAMES.get(matcher, matcher)] + cells)
    return rows


def _reason_counts(result) -> list[tuple[str, int]]:
    counts: dict[str, int] = {}
    seen = set()
    for row in result.rows:
        key = (row.map, row.model, row.matcher, row.variant, row.m_label)
        if not row.reason or key in seen:
            continue
        seen.add(key)
        # Reasons quote the m; group runs by the words around it.
        generic = row.reason.replace(f"m = {row.m_value:g}", "m = ...")
        counts[generic] = counts.get(generic, 0) + 1
    return sorted(counts.items(), key=lambda item: -item[1])[:15]


# --------------------------------------------------------------------------- files


def write_report(result, out_dir: str | Path) -> dict[str, Path]:
    """Write runs.csv, summary.md, f1_vs_m.png, place_vs_m.png and boxplots.png into ``out_dir``.

    The folder is created if needed; each file is written atomically, so an interrupted run
    leaves every file either complete or at its previous version.

    Returns
    -------
    dict of str to Path
        File name -> path written.

    Examples
    --------
    >>> import tempfile
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, 1.0, 1, 3, 3, 0.0)]
    >>> sorted(write_report(EvaluationResult(rows=tuple(rows)), tempfile.mkdtemp()))
    ['boxplots.png', 'f1_vs_m.png', 'place_vs_m.png', 'runs.csv', 'summary.md']
    """
    from ursim_core.io.atomic import atomic_write_bytes, atomic_write_text

    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    written = {}
    contents: list[tuple[str, str | bytes]] = [
        ("runs.csv", runs_csv(result)),
        ("f1_vs_m.png", plot_f1_vs_m(result)),
        ("place_vs_m.png", plot_place_vs_m(result)),
        ("boxplots.png", plot_boxplots(result)),
        ("summary.md", markdown_summary(result)),
    ]
    for name, content in contents:
        path = folder / name
        if isinstance(content, bytes):
            atomic_write_bytes(path, content)
        else:
            atomic_write_text(path, content)
        written[name] = path
    return written
