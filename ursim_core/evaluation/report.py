"""Reports of an evaluation: Table-1-style text, runs.csv, plots and a markdown summary.

Everything here is a pure function of an :class:`ursim_core.evaluation.runner.EvaluationResult`
(its ``rows``, ``human_rows``, ``summaries``, ``settings`` and ``timings``), except
:func:`write_report`, which writes the files atomically.

The published figures quoted for comparison are constants below, each with its source.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "PAPER_TABLE1",
    "PAPER_HUMAN_VS_HUMAN",
    "PAPER_FIXED_M",
    "PAPER_E5",
    "RELEASED_KTH",
    "RELEASED_BASELINES",
    "RELEASED_E5",
    "runs_csv",
    "format_tables",
    "markdown_summary",
    "plot_f1_vs_m",
    "plot_boxplots",
    "write_report",
]

# --------------------------------------------------------------------------- published figures

#: Mielle et al., "URSIM", Robotics 8(2):43, 2019, Table 1: sketch dataset (25 sketches, both
#: annotators), F1 with m chosen per map as the best of 0 .. 1 in steps of 0.025 (an oracle).
#: ``median`` values and ``mean`` as (mean, sd). Quoted from shared/design/paper.md.
PAPER_TABLE1: dict[str, dict[str, dict[str, Any]]] = {
    "hungarian": {
        "median": {"baseline": 0.27, "T1": 0.50, "T2": 0.42, "T3": 0.40, "T4": 0.47},
        "mean": {
            "baseline": (0.27, 0.23),
            "T1": (0.48, 0.24),
            "T2": (0.47, 0.24),
            "T3": (0.42, 0.22),
            "T4": (0.50, 0.24),
        },
    },
    "vf2": {
        "median": {"baseline": 0.00, "T1": 0.00, "T2": 0.00, "T3": 0.00, "T4": 0.00},
        "mean": {
            "baseline": (0.03, 0.17),
            "T1": (0.22, 0.33),
            "T2": (0.22, 0.33),
            "T3": (0.13, 0.29),
            "T4": (0.13, 0.29),
        },
    },
    "planar": {
        "median": {"baseline": 0.67, "T1": 0.74, "T2": 0.67, "T3": 0.67, "T4": 0.80},
        "mean": {
            "baseline": (0.61, 0.30),
            "T1": (0.68, 0.28),
            "T2": (0.70, 0.23),
            "T3": (0.70, 0.25),
            "T4": (0.73, 0.22),
        },
    },
}
#: Same paper, one annotator's cliques scored against the other's (shared/design/paper.md).
PAPER_HUMAN_VS_HUMAN = {"median": 0.89, "mean": 0.84, "sd": 0.16}
#: Same paper, Section 6.4: one fixed m for all sketches, URSIM planar (shared/design/paper.md).
PAPER_FIXED_M = {"m": 0.15, "median": 0.67, "mean": 0.57}
#: Same paper, Table 2: Halmstad E5 partial sensor maps, oracle m (shared/design/paper.md).
#: (median, mean, sd); DAM is the metric-alignment method of Gholami Shahbandi et al.
PAPER_E5 = {"planar T4 (URSIM)": (0.37, 0.39, 0.22), "planar T2": (0.48, 0.46, 0.18), "DAM": (0.94, 0.78, 0.31)}

#: The authors' released C++ run on the 18 KTH sketches here, URSIM planar (T4), released
#: segmentation (t = 0.5, non-zero = free), m swept 0 .. 0.475. Quoted from
#: shared/design/released_code_results.md. "fnfix": the released scorer with its
#: uninitialised false-negative flag set to false; "as-built": what the -O2 binary printed
#: (FN always 0). Per annotator: oracle (mean, median); best fixed (m, mean, median).
RELEASED_KTH = {
    "fnfix": {
        "oracle": {"malcolm": (0.568, 0.633), "vasiliki": (0.562, 0.550)},
        "fixed": {"malcolm": (0.125, 0.487, 0.450), "vasiliki": (0.125, 0.475, 0.400)},
    },
    "as-built": {
        "oracle": {"malcolm": (0.771, 0.857), "vasiliki": (0.754, 0.829)},
        "fixed": {"malcolm": (0.125, 0.661, 0.733), "vasiliki": (0.175, 0.658, 0.667)},
    },
}
#: Same source: baselines on all 26 sketches (fnfix), mean F1 (malcolm, vasiliki).
RELEASED_BASELINES = {"hungarian": (0.310, 0.262), "vf2": (0.099, 0.096)}
#: Same source: Halmstad E5 robot maps (10 per annotator), fnfix mean F1 (malcolm, vasiliki).
RELEASED_E5 = {"planar T4 oracle": (0.343, 0.340), "hungarian": (0.145, 0.125), "vf2": (0.0, 0.0)}

_CHOICE_TITLES = {
    "oracle": "oracle m (best m of the grid for each map)",
    "fixed": "best single fixed m (highest mean F1 over the maps)",
    "auto": "automatic m",
}
_MATCHER_NAMES = {"planar": "Planar", "hungarian": "Hungarian", "vf2": "VF2"}
_VARIANT_NAMES = {"baseline": "Baseline", "T1": "T1", "T2": "T2", "T3": "T3", "T4": "T4"}


# --------------------------------------------------------------------------- CSV


def runs_csv(result) -> str:
    """Every run (matcher rows, then human-vs-human rows) as CSV text, one row per RunRow.

    Floats are written with 6 significant digits; a NaN (the m of a human row) is empty.

    Examples
    --------
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> row = RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 1, 0, 0.5, 1.0, 2 / 3, 4, 5, 6, 0.01)
    >>> runs_csv(EvaluationResult(rows=(row,))).splitlines()[1]
    '00,a,planar,T4,0.1,0.1,1,1,0,0.5,1,0.666667,4,5,6,0.01,,0,correct,'
    """
    from ursim_core.evaluation.runner import RUN_COLUMNS

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(RUN_COLUMNS)
    for row in (*result.rows, *result.human_rows):
        writer.writerow([_csv_value(getattr(row, column)) for column in RUN_COLUMNS])
    return buffer.getvalue()


def _csv_value(value: Any) -> Any:
    if isinstance(value, float):
        return "" if math.isnan(value) else format(value, ".6g")
    return value


# --------------------------------------------------------------------------- tables


def _number(value: float) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.2f}"


def _mean_sd(mean: float, sd: float) -> str:
    if mean is None or math.isnan(mean):
        return "-"
    return f"{mean:.2f} ± {sd:.2f}" if not math.isnan(sd) else f"{mean:.2f}"


def _methods(result) -> tuple[list[str], list[str]]:
    from ursim_core.evaluation.runner import MATCHERS, VARIANTS

    present_matchers = {s.matcher for s in result.summaries}
    present_variants = {s.variant for s in result.summaries}
    matchers = [m for m in result.settings.get("matchers", MATCHERS) if m in present_matchers]
    variants = [v for v in result.settings.get("variants", VARIANTS) if v in present_variants]
    # Paper order of the columns whatever order they were run in.
    variants.sort(key=lambda v: VARIANTS.index(v) if v in VARIANTS else len(VARIANTS))
    return matchers, variants


def _annotator_groups(result) -> list[str]:
    return list(dict.fromkeys(s.annotator for s in result.summaries))


def _table1(result, annotator: str, choice: str) -> tuple[list[str], list[list[str]], int]:
    """Header, rows and number of maps of one Table-1-style table."""
    matchers, variants = _methods(result)
    header = ["matcher"] + [_VARIANT_NAMES.get(v, v) for v in variants]
    cells = {(m, v): result.summary(annotator, m, v, choice) for m in matchers for v in variants}
    rows = []
    for matcher in matchers:
        rows.append(
            [f"{_MATCHER_NAMES.get(matcher, matcher)} median"]
            + [_number(cells[matcher, v].median if cells[matcher, v] else None) for v in variants]
        )
    for matcher in matchers:
        rows.append(
            [f"{_MATCHER_NAMES.get(matcher, matcher)} mean"]
            + [_mean_sd(cells[matcher, v].mean, cells[matcher, v].sd) if cells[matcher, v] else "-" for v in variants]
        )
    if choice == "fixed":
        for matcher in matchers:
            rows.append(
                [f"{_MATCHER_NAMES.get(matcher, matcher)} best m"]
                + [cells[matcher, v].fixed_m if cells[matcher, v] else "-" for v in variants]
            )
    if choice == "auto":
        for matcher in matchers:
            rows.append(
                [f"{_MATCHER_NAMES.get(matcher, matcher)} median m"]
                + [_m_text(_median(cells[matcher, v].m_values)) if cells[matcher, v] else "-" for v in variants]
            )
    n_maps = max((s.n for s in cells.values() if s is not None), default=0)
    return header, rows, n_maps


def _median(values: Sequence[float]) -> float:
    import statistics

    values = [v for v in values if not math.isnan(v)]
    return float(statistics.median(values)) if values else math.nan


def _m_text(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.3g}"


def _paper_table1(variants: Sequence[str], matchers: Sequence[str]) -> tuple[list[str], list[list[str]]]:
    header = ["matcher"] + [_VARIANT_NAMES.get(v, v) for v in variants]
    rows = []
    for stat in ("median", "mean"):
        for matcher in matchers:
            if matcher not in PAPER_TABLE1:
                continue
            values = PAPER_TABLE1[matcher][stat]
            cells = []
            for variant in variants:
                value = values.get(variant)
                if value is None:
                    cells.append("-")
                elif stat == "median":
                    cells.append(_number(value))
                else:
                    cells.append(_mean_sd(*value))
            rows.append([f"{_MATCHER_NAMES.get(matcher, matcher)} {stat}"] + cells)
    return header, rows


def _text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(str(line[i])) for line in [header, *rows]) for i in range(len(header))]
    lines = []
    for line in [header, *rows]:
        lines.append("  ".join(str(cell).ljust(width) for cell, width in zip(line, widths)).rstrip())
    return "\n".join(lines)


def _markdown_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def _human_lines(result) -> list[str]:
    lines = []
    for item in result.human_summaries:
        lines.append(
            f"Human vs human ({item.variant}'s cliques scored against {item.annotator}'s): "
            f"median {_number(item.median)}, mean {_mean_sd(item.mean, item.sd)} ({item.n} maps)"
        )
    return lines


def _scoring_name(result) -> str:
    return {"correct": "correct", "as-built": "legacy (released binary, FN = 0)", "fnfix": "legacy fnfix"}.get(
        result.settings.get("scoring", "correct"), str(result.settings.get("scoring"))
    )


def _heading(result) -> list[str]:
    settings, timings = result.settings, result.timings
    grid = settings.get("m_grid") or []
    grid_text = f"{len(grid)} values {min(grid):g} .. {max(grid):g}" if grid else "none"
    lines = [
        f"URSIM evaluation of {settings.get('dataset') or 'the given experiments'}: "
        f"{settings.get('n_experiments', len(result.experiments))} experiments, scoring {_scoring_name(result)}",
        f"segmentation presets {', '.join(settings.get('presets_used', [])) or '-'}; m grid {grid_text}"
        + (" + auto" if settings.get("auto_m", True) else "")
        + ("; released-code configuration" if settings.get("released") else ""),
    ]
    if timings:
        lines.append(
            f"time: segmentation {timings.get('segmentation_s', 0):.1f} s "
            f"({timings.get('maps', 0)} maps, {timings.get('maps_from_cache', 0)} from cache), "
            f"matching {timings.get('matching_s', 0):.1f} s, total {timings.get('total_s', 0):.1f} s "
            f"on {settings.get('workers', 1)} worker(s)"
        )
    return lines


def _comparison_lines(result) -> list[str]:
    scoring = result.settings.get("scoring", "correct")
    released = RELEASED_KTH["as-built" if scoring == "as-built" else "fnfix"]
    label = "as-built" if scoring == "as-built" else "fnfix"
    lines = [
        "Published figures (other segmentation, data or scoring: compare trends, not decimals):",
        f"  paper Table 1, planar T4 (oracle m over 0..1, 25 sketches): median {PAPER_TABLE1['planar']['median']['T4']:.2f}, "
        f"mean {_mean_sd(*PAPER_TABLE1['planar']['mean']['T4'])}; fixed m = {PAPER_FIXED_M['m']}: "
        f"median {PAPER_FIXED_M['median']:.2f}, mean {PAPER_FIXED_M['mean']:.2f}; human vs human: "
        f"median {PAPER_HUMAN_VS_HUMAN['median']:.2f}, mean {_mean_sd(PAPER_HUMAN_VS_HUMAN['mean'], PAPER_HUMAN_VS_HUMAN['sd'])}",
        f"  released C++ on these 18 KTH sketches, planar T4, {label} scoring: oracle mean/median "
        + ", ".join(f"{a} {v[0]:.3f}/{v[1]:.3f}" for a, v in released["oracle"].items())
        + "; best fixed m "
        + ", ".join(f"{a} m={v[0]:g} mean {v[1]:.3f}" for a, v in released["fixed"].items()),
    ]
    return lines


def format_tables(result) -> str:
    """Table-1-style text tables (rows = matcher, columns = variants) for the terminal.

    One table per annotator (then all annotators pooled) and per choice of m (oracle, best fixed,
    automatic), the human-vs-human lines, and the published figures for comparison.

    Examples
    --------
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> rows = [RunRow(name, "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, f1, 1, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> text = format_tables(EvaluationResult(rows=tuple(rows), settings={"matchers": ["planar"], "variants": ["T4"]}))
    >>> [line for line in text.splitlines() if line.startswith("Planar mean")][0]
    'Planar mean    0.75 ± 0.35'
    """
    lines = _heading(result)
    for annotator in _annotator_groups(result):
        who = "all annotators pooled" if annotator == _pooled() else f"annotator {annotator}"
        for choice in ("oracle", "fixed", "auto"):
            header, rows, n_maps = _table1(result, annotator, choice)
            if not n_maps:
                continue
            lines += ["", f"F1, {_CHOICE_TITLES[choice]}, {who}, {n_maps} maps", _text_table(header, rows)]
    human = _human_lines(result)
    if human:
        lines += [""] + human
    lines += [""] + _comparison_lines(result)
    return "\n".join(lines) + "\n"


def _pooled() -> str:
    from ursim_core.evaluation.runner import POOLED

    return POOLED


# --------------------------------------------------------------------------- markdown


def markdown_summary(result, *, files: Sequence[str] = ("runs.csv", "f1_vs_m.png", "boxplots.png")) -> str:
    """The summary.md text: settings, Table-1-style tables, F1 per m, published figures, notes.

    Examples
    --------
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, 1.0, 1, 3, 3, 0.0)]
    >>> "| Planar median | 1.00 |" in markdown_summary(EvaluationResult(rows=tuple(rows)))
    True
    """
    from ursim_core.evaluation.runner import mean_f1_by_m

    settings = result.settings
    lines = ["# URSIM evaluation", ""]
    lines += [f"- {line}" for line in _heading(result)]
    config = settings.get("config")
    if config:
        lines.append("- matching configuration: " + ", ".join(f"`{k}={v}`" for k, v in config.items() if k != "m_grid"))
    lines.append("- files: " + ", ".join(f"[{name}]({name})" for name in files))
    lines.append("")
    lines += [
        "F1 per map pair, then median and mean ± sample sd over the maps. *Oracle* picks the best m of the grid",
        "for each map (as the paper's Table 1), *best fixed m* the single m with the highest mean F1, *automatic m*",
        "the matcher's own choice. Ground-truth points are mapped onto the evaluated segmentation (10 px tolerance).",
        "",
    ]
    for annotator in _annotator_groups(result):
        who = (
            "all annotators pooled (one sample per map and annotator)"
            if annotator == _pooled()
            else f"annotator {annotator}"
        )
        lines += [f"## {who}", ""]
        for choice in ("oracle", "fixed", "auto"):
            header, rows, n_maps = _table1(result, annotator, choice)
            if not n_maps:
                continue
            lines += [f"### F1, {_CHOICE_TITLES[choice]} ({n_maps} maps)", "", _markdown_table(header, rows), ""]
        precision_rows = _precision_recall_rows(result, annotator)
        if precision_rows:
            lines += [
                "### Mean precision / recall at the oracle m",
                "",
                _markdown_table(["matcher", *_variant_header(result)], precision_rows),
                "",
            ]

    human = _human_lines(result)
    if human:
        lines += ["## Human vs human", ""] + [f"- {line}" for line in human] + [""]

    by_m = mean_f1_by_m(result.rows)
    if by_m:
        lines += ["## Mean F1 for each fixed m", ""]
        annotators = list(dict.fromkeys(key[0] for key in by_m))
        for annotator in annotators:
            keys = [key for key in by_m if key[0] == annotator]
            labels = sorted({(m, label) for key in keys for m, label, _, _ in by_m[key]})
            header = ["m"] + [f"{_MATCHER_NAMES.get(k[1], k[1])} {_VARIANT_NAMES.get(k[2], k[2])}" for k in keys]
            table_rows = []
            for _m_value, label in labels:
                values = {key: {lab: mean for _, lab, mean, _ in by_m[key]} for key in keys}
                table_rows.append([label] + [_number(values[key].get(label, math.nan)) for key in keys])
            lines += [f"### {annotator}", "", _markdown_table(header, table_rows), ""]

    lines += ["## Published figures for comparison", ""]
    lines += _published_markdown(result)
    if result.notes:
        lines += ["## Notes", ""] + [f"- {note}" for note in result.notes] + [""]
    reasons = _reason_counts(result)
    if reasons:
        lines += ["## Degenerate runs (reason reported by the matcher, count of runs)", ""]
        lines += [f"- {count} x {reason}" for reason, count in reasons] + [""]
    return "\n".join(lines).rstrip() + "\n"


def _variant_header(result) -> list[str]:
    return [_VARIANT_NAMES.get(v, v) for v in _methods(result)[1]]


def _precision_recall_rows(result, annotator: str) -> list[list[str]]:
    matchers, variants = _methods(result)
    rows = []
    for matcher in matchers:
        cells = []
        for variant in variants:
            item = result.summary(annotator, matcher, variant, "oracle")
            cells.append("-" if item is None else f"{_number(item.mean_precision)} / {_number(item.mean_recall)}")
        rows.append([_MATCHER_NAMES.get(matcher, matcher)] + cells)
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


def _published_markdown(result) -> list[str]:
    from ursim_core.evaluation.runner import VARIANTS

    header, rows = _paper_table1(VARIANTS, ("hungarian", "vf2", "planar"))
    lines = [
        "Mielle et al. 2019, Table 1 (25 KTH sketches, both annotators, oracle m over 0 .. 1 step 0.025;",
        "scoring as implemented by the released code; segmentation as the released driver):",
        "",
        _markdown_table(header, rows),
        "",
        f"- Fixed m for all sketches (Section 6.4): best around m = {PAPER_FIXED_M['m']}, median {PAPER_FIXED_M['median']:.2f}, mean {PAPER_FIXED_M['mean']:.2f}.",
        f"- Human vs human: median {PAPER_HUMAN_VS_HUMAN['median']:.2f}, mean {_mean_sd(PAPER_HUMAN_VS_HUMAN['mean'], PAPER_HUMAN_VS_HUMAN['sd'])}.",
        "- Halmstad E5 (Table 2), median / mean ± sd: "
        + "; ".join(f"{name} {v[0]:.2f} / {_mean_sd(v[1], v[2])}" for name, v in PAPER_E5.items())
        + ".",
        "",
        "The authors' released C++ on the 18 KTH sketches of this dataset (planar T4, released segmentation,",
        "m 0 .. 0.475; `released_code_results.md`). Comparable to a run with the released configuration and the same scoring:",
        "",
    ]
    table_rows = []
    for scoring, figures in RELEASED_KTH.items():
        for annotator in ("malcolm", "vasiliki"):
            oracle_mean, oracle_median = figures["oracle"][annotator]
            fixed_m, fixed_mean, fixed_median = figures["fixed"][annotator]
            table_rows.append(
                [
                    scoring,
                    annotator,
                    f"{oracle_median:.3f}",
                    f"{oracle_mean:.3f}",
                    f"{fixed_m:g}",
                    f"{fixed_median:.3f}",
                    f"{fixed_mean:.3f}",
                ]
            )
    lines += [
        _markdown_table(
            ["scoring", "annotator", "oracle median", "oracle mean", "best fixed m", "fixed median", "fixed mean"],
            table_rows,
        ),
        "",
        "- Baselines on all 26 sketches (fnfix, mean F1 malcolm / vasiliki): "
        + "; ".join(f"{_MATCHER_NAMES[k]} {v[0]:.3f} / {v[1]:.3f}" for k, v in RELEASED_BASELINES.items())
        + ".",
        "- Halmstad E5 (fnfix, mean F1 malcolm / vasiliki): "
        + "; ".join(f"{k} {v[0]:.3f} / {v[1]:.3f}" for k, v in RELEASED_E5.items())
        + ".",
        "",
    ]
    return lines


# --------------------------------------------------------------------------- plots


def _png(figure) -> bytes:
    buffer = io.BytesIO()
    # The layout is already tight (tight_layout); bbox_inches="tight" would draw everything twice.
    figure.savefig(buffer, format="png", dpi=100)
    import matplotlib.pyplot as plt

    plt.close(figure)
    return buffer.getvalue()


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_f1_vs_m(result) -> bytes:
    """PNG of mean F1 against m: one panel per matcher x annotator, one line per variant.

    The mean F1 with the automatic m is drawn as a dashed horizontal line of the variant's colour.

    Examples
    --------
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", label, m, 1, 0, 0, 1.0, 1.0, m, 1, 3, 3, 0.0)
    ...         for label, m in (("0", 0.0), ("0.1", 0.1))]
    >>> plot_f1_vs_m(EvaluationResult(rows=tuple(rows)))[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
    True
    """
    from ursim_core.evaluation.runner import POOLED, mean_f1_by_m

    plt = _pyplot()
    by_m = mean_f1_by_m(result.rows)
    matchers, variants = _methods(result)
    annotators = [a for a in _annotator_groups(result) if a != POOLED]
    if not by_m or not matchers or not annotators:
        return _empty_plot(plt, "no fixed-m runs to plot")
    colours = plt.get_cmap("tab10")
    figure, axes = plt.subplots(
        len(matchers),
        len(annotators),
        figsize=(5.2 * len(annotators), 3.3 * len(matchers)),
        squeeze=False,
        sharex=True,
        sharey=True,
    )
    for row_index, matcher in enumerate(matchers):
        for col_index, annotator in enumerate(annotators):
            axis = axes[row_index][col_index]
            for variant_index, variant in enumerate(variants):
                colour = colours(variant_index % 10)
                points = by_m.get((annotator, matcher, variant))
                if points:
                    axis.plot(
                        [p[0] for p in points],
                        [p[2] for p in points],
                        marker=".",
                        color=colour,
                        label=_VARIANT_NAMES.get(variant, variant),
                    )
                auto = result.summary(annotator, matcher, variant, "auto")
                if auto is not None and auto.n:
                    axis.axhline(auto.mean, color=colour, linestyle="--", linewidth=1)
            axis.set_title(f"{_MATCHER_NAMES.get(matcher, matcher)}, {annotator}", fontsize=10)
            axis.set_ylim(0, 1.02)
            axis.grid(alpha=0.3)
            if row_index == len(matchers) - 1:
                axis.set_xlabel("m")
            if col_index == 0:
                axis.set_ylabel("mean F1 over maps")
    handles, labels = axes[0][0].get_legend_handles_labels()
    from matplotlib.lines import Line2D

    handles.append(Line2D([], [], color="grey", linestyle="--"))
    labels.append("automatic m (mean)")
    figure.legend(handles, labels, loc="upper center", ncol=len(labels), frameon=False, bbox_to_anchor=(0.5, 1.0))
    figure.tight_layout(rect=(0, 0, 1, 1 - 0.35 / figure.get_figheight()))
    return _png(figure)


def plot_boxplots(result) -> bytes:
    """PNG of the F1 distributions: one panel per choice of m (oracle, best fixed, automatic).

    Each panel has a group of boxes per matcher x variant, one box per annotator, and the
    human-vs-human distributions at the right when there are some.

    Examples
    --------
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> rows = [RunRow(name, "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, f1, 1, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> plot_boxplots(EvaluationResult(rows=tuple(rows)))[:4] == b"\\x89PNG"
    True
    """
    from ursim_core.evaluation.runner import POOLED

    plt = _pyplot()
    matchers, variants = _methods(result)
    annotators = [a for a in _annotator_groups(result) if a != POOLED]
    choices = [c for c in ("oracle", "fixed", "auto") if any(s.choice == c for s in result.summaries)]
    if not choices or not annotators:
        return _empty_plot(plt, "no runs to plot")
    colours = plt.get_cmap("Set2")
    methods = [(m, v) for m in matchers for v in variants]
    humans = list(result.human_summaries)
    width = 0.8 / len(annotators)
    figure, axes = plt.subplots(
        len(choices),
        1,
        figsize=(
            max(7.0, 0.75 * (len(methods) + len(humans)) * max(1, len(annotators)) ** 0.5 + 2),
            3.2 * len(choices),
        ),
        squeeze=False,
        sharey=True,
    )
    tick_labels = [f"{_MATCHER_NAMES.get(m, m)}\n{_VARIANT_NAMES.get(v, v)}" for m, v in methods]
    tick_labels += [f"human\n{h.variant} vs {h.annotator}" for h in humans]
    for axis, choice in zip((row[0] for row in axes), choices):
        for annotator_index, annotator in enumerate(annotators):
            data, positions = [], []
            for method_index, (matcher, variant) in enumerate(methods):
                item = result.summary(annotator, matcher, variant, choice)
                if item is not None and item.n:
                    data.append(list(item.f1))
                    positions.append(method_index - 0.4 + width * (annotator_index + 0.5))
            if data:
                boxes = axis.boxplot(
                    data,
                    positions=positions,
                    widths=width * 0.9,
                    patch_artist=True,
                    manage_ticks=False,
                    medianprops={"color": "black"},
                )
                for patch in boxes["boxes"]:
                    patch.set_facecolor(colours(annotator_index % 8))
                axis.plot([], [], color=colours(annotator_index % 8), linewidth=8, label=annotator)
        if humans:
            data = [list(h.f1) for h in humans]
            positions = [len(methods) + i for i in range(len(humans))]
            boxes = axis.boxplot(
                data,
                positions=positions,
                widths=0.5,
                patch_artist=True,
                manage_ticks=False,
                medianprops={"color": "black"},
            )
            for patch in boxes["boxes"]:
                patch.set_facecolor("lightgrey")
        axis.set_xticks(range(len(tick_labels)))
        axis.set_xticklabels(tick_labels, fontsize=7)
        axis.set_ylim(-0.02, 1.02)
        axis.set_ylabel("F1")
        axis.set_title(f"F1 per map, {_CHOICE_TITLES[choice]}", fontsize=10)
        axis.grid(axis="y", alpha=0.3)
    figure.legend(
        *axes[0][0].get_legend_handles_labels(),
        loc="upper center",
        ncol=len(annotators),
        frameon=False,
        fontsize=9,
        bbox_to_anchor=(0.5, 1.0),
    )
    figure.tight_layout(rect=(0, 0, 1, 1 - 0.3 / figure.get_figheight()))
    return _png(figure)


def _empty_plot(plt, message: str) -> bytes:
    figure, axis = plt.subplots(figsize=(4, 2))
    axis.axis("off")
    axis.text(0.5, 0.5, message, ha="center", va="center")
    return _png(figure)


# --------------------------------------------------------------------------- files


def write_report(result, out_dir: str | Path) -> dict[str, Path]:
    """Write runs.csv, summary.md, f1_vs_m.png and boxplots.png into ``out_dir``.

    The folder is created if needed; each file is written atomically, so an interrupted run
    leaves every file either complete or at its previous version.

    Returns
    -------
    dict of str to Path
        File name -> path written.

    Examples
    --------
    >>> import tempfile
    >>> from ursim_core.evaluation.runner import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, 1.0, 1, 3, 3, 0.0)]
    >>> sorted(write_report(EvaluationResult(rows=tuple(rows)), tempfile.mkdtemp()))
    ['boxplots.png', 'f1_vs_m.png', 'runs.csv', 'summary.md']
    """
    from ursim_core.io.atomic import atomic_write_bytes, atomic_write_text

    folder = Path(out_dir)
    folder.mkdir(parents=True, exist_ok=True)
    written = {}
    contents: list[tuple[str, str | bytes]] = [
        ("runs.csv", runs_csv(result)),
        ("f1_vs_m.png", plot_f1_vs_m(result)),
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
