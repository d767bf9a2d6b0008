"""Table-1-style text tables of an evaluation (rows = matcher, columns = variants) for the terminal."""

from __future__ import annotations

import math
import statistics

from ursim_core.evaluation.formatting import (
    CHOICE_TITLES,
    MATCHER_NAMES,
    VARIANT_NAMES,
    m_text,
    mean_sd,
    median,
    number,
    text_table,
)
from ursim_core.evaluation.published import comparison_lines
from ursim_core.evaluation.results import MATCHERS, POOLED, VARIANTS

__all__ = [
    "format_tables",
    "methods",
    "annotator_groups",
    "table1",
    "heading",
    "human_lines",
    "ceiling_lines",
    "headline_choice",
    "per_sample",
    "orientation_table",
    "per_sketch_table",
]


def methods(result) -> tuple[list[str], list[str]]:

    present_matchers = {s.matcher for s in result.summaries}
    present_variants = {s.variant for s in result.summaries}
    matchers = [m for m in result.settings.get("matchers", MATCHERS) if m in present_matchers]
    variants = [v for v in result.settings.get("variants", VARIANTS) if v in present_variants]
    # Paper order of the columns whatever order they were run in.
    variants.sort(key=lambda v: VARIANTS.index(v) if v in VARIANTS else len(VARIANTS))
    return matchers, variants


def annotator_groups(result) -> list[str]:
    return list(dict.fromkeys(s.annotator for s in result.summaries))


def table1(result, annotator: str, choice: str) -> tuple[list[str], list[list[str]], int]:
    """Header, rows and number of maps of one Table-1-style table."""
    matchers, variants = methods(result)
    header = ["matcher"] + [VARIANT_NAMES.get(v, v) for v in variants]
    cells = {(m, v): result.summary(annotator, m, v, choice) for m in matchers for v in variants}
    rows = []
    for matcher in matchers:
        rows.append(
            [f"{MATCHER_NAMES.get(matcher, matcher)} median"]
            + [number(cells[matcher, v].median if cells[matcher, v] else None) for v in variants]
        )
    for matcher in matchers:
        rows.append(
            [f"{MATCHER_NAMES.get(matcher, matcher)} mean"]
            + [mean_sd(cells[matcher, v].mean, cells[matcher, v].sd) if cells[matcher, v] else "-" for v in variants]
        )
    for matcher in matchers:
        rows.append(
            [f"{MATCHER_NAMES.get(matcher, matcher)} place"]
            + [number(cells[matcher, v].mean_place) if cells[matcher, v] else "-" for v in variants]
        )
    if choice == "fixed":
        for matcher in matchers:
            rows.append(
                [f"{MATCHER_NAMES.get(matcher, matcher)} best m"]
                + [cells[matcher, v].fixed_m if cells[matcher, v] else "-" for v in variants]
            )
    if choice == "auto":
        for matcher in matchers:
            rows.append(
                [f"{MATCHER_NAMES.get(matcher, matcher)} median m"]
                + [m_text(median(cells[matcher, v].m_values)) if cells[matcher, v] else "-" for v in variants]
            )
    n_maps = max((s.n for s in cells.values() if s is not None), default=0)
    return header, rows, n_maps


def human_lines(result) -> list[str]:
    lines = []
    for item in result.human_summaries:
        lines.append(
            f"Human vs human ({item.variant}'s cliques scored against {item.annotator}'s): "
            f"F1 median {number(item.median)}, mean {mean_sd(item.mean, item.sd)}; "
            f"place accuracy mean {number(item.mean_place)} ({item.n} maps)"
        )
    return lines


def ceiling_lines(result) -> list[str]:
    """The one-to-one ceiling (:mod:`ursim_core.evaluation.ceiling`) in one line, or none."""
    item = result.ceiling_summary
    if item is None:
        return []
    bound = "" if item.variant == "one-to-one" else "; a lower bound: the search stopped at its node budget"
    return [
        "Ceiling (the best one-to-one answer against every annotator at once, found by exhaustive search): "
        f"F1 median {number(item.median)}, mean {mean_sd(item.mean, item.sd)}; "
        f"place accuracy mean {number(item.mean_place)} ({item.n} maps x annotators{bound})"
    ]


def headline_choice(result) -> str:
    """The choice of m of the per-orientation and per-sketch tables: automatic when it was run."""
    choices = {s.choice for s in result.summaries}
    return next((c for c in ("auto", "fixed", "oracle") if c in choices), "auto")


def _group(result) -> str:
    # The pooled group when there is one, else the single annotator.
    groups = annotator_groups(result)
    return POOLED if POOLED in groups else (groups[0] if groups else POOLED)


def per_sample(summary) -> dict[tuple[str, str], tuple[float, float]]:
    """``(map, orientation) -> (mean F1, mean place accuracy)`` over the annotators of a summary.

    Examples
    --------
    >>> from ursim_core.evaluation.results import Summary
    >>> s = Summary("all", "planar", "T4", "auto", ("00@rot0/a", "00@rot0/b", "00@rot90/a"),
    ...             (1.0, 0.5, 0.0), (1, 1, 1), (1, 1, 1), (0.1, 0.1, 0.1), place=(1.0, 0.0, 0.0))
    >>> per_sample(s)
    {('00', 'rot0'): (0.75, 0.5), ('00', 'rot90'): (0.0, 0.0)}
    """
    values: dict[tuple[str, str], list[tuple[float, float]]] = {}
    places = summary.place or (math.nan,) * len(summary.f1)
    for name, f1, place in zip(summary.maps, summary.f1, places):
        sample = name.rsplit("/", 1)[0] if summary.annotator == POOLED else name
        map_name, _, augment = sample.partition("@")
        values.setdefault((map_name, augment), []).append((f1, place))
    return {key: (_mean([v[0] for v in items]), _mean([v[1] for v in items])) for key, items in values.items()}


def _mean(values) -> float:
    values = [v for v in values if not math.isnan(v)]
    return float(statistics.fmean(values)) if values else math.nan


def _pair(f1: float, place: float) -> str:
    return f"{number(f1)} / {number(place)}"


def orientation_table(result, choice: str | None = None) -> tuple[list[str], list[list[str]]] | None:
    """Mean F1 / place accuracy per orientation (rows) and matcher x variant (columns), or None
    when the run was not augmented. The last row is the worst orientation of each column."""
    orientations = result.settings.get("augment") or []
    if not orientations:
        return None
    choice = choice or headline_choice(result)
    matchers, variants = methods(result)
    group = _group(result)
    columns = [(m, v) for m in matchers for v in variants]
    samples = {}
    for matcher, variant in columns:
        summary = result.summary(group, matcher, variant, choice)
        samples[matcher, variant] = per_sample(summary) if summary is not None else {}
    header = ["orientation"] + [f"{MATCHER_NAMES.get(m, m)} {VARIANT_NAMES.get(v, v)}" for m, v in columns]
    rows = []
    worst: dict[tuple[str, str], tuple[float, float]] = {}
    for orientation in orientations:
        cells = []
        for column in columns:
            items = [value for (_, augment), value in samples[column].items() if augment == orientation]
            f1, place = _mean([v[0] for v in items]), _mean([v[1] for v in items])
            cells.append(_pair(f1, place))
            if not math.isnan(f1) and (column not in worst or f1 < worst[column][0]):
                worst[column] = (f1, place)
        rows.append([orientation, *cells])
    rows.append(["worst"] + [_pair(*worst.get(column, (math.nan, math.nan))) for column in columns])
    return header, rows


def per_sketch_table(result, matcher: str, variant: str, choice: str | None = None):
    """F1 / place accuracy per sketch (rows) and orientation (columns) of one matcher x variant,
    averaged over the annotators; None when that method was not run."""
    choice = choice or headline_choice(result)
    summary = result.summary(_group(result), matcher, variant, choice)
    if summary is None:
        return None
    samples = per_sample(summary)
    orientations = result.settings.get("augment") or [""]
    maps = list(dict.fromkeys(name for name, _ in samples))
    header = ["map"] + [orientation or "F1 / place" for orientation in orientations]
    rows = [
        [name] + [_pair(*samples.get((name, orientation), (math.nan, math.nan))) for orientation in orientations]
        for name in maps
    ]
    ceiling = result.ceiling_summary
    if ceiling is not None:
        # One column: the best one-to-one answer's mean over the orientations run.
        by_map: dict[str, list[tuple[float, float]]] = {}
        for (name, _), value in per_sample(ceiling).items():
            by_map.setdefault(name, []).append(value)
        header.append("ceiling")
        for row in rows:
            values = by_map.get(row[0], [])
            row.append(_pair(_mean([v[0] for v in values]), _mean([v[1] for v in values])))
    return header, rows


def _scoring_name(result) -> str:
    return {"correct": "correct", "as-built": "legacy (released binary, FN = 0)", "fnfix": "legacy fnfix"}.get(
        result.settings.get("scoring", "correct"), str(result.settings.get("scoring"))
    )


def heading(result) -> list[str]:
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
            + (
                f"on the Dask cluster {settings['scheduler']}"
                if settings.get("scheduler")
                else f"on {settings.get('workers', 1)} worker(s)"
            )
        )
    return lines


def format_tables(result) -> str:
    """Table-1-style text tables (rows = matcher, columns = variants) for the terminal.

    One table per annotator (then all annotators pooled) and per choice of m (oracle, best fixed,
    automatic), with the mean place accuracy of each cell (``place`` rows); a per-orientation
    table when the run was augmented; the human-vs-human lines, and the published figures.

    Examples
    --------
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> rows = [RunRow(name, "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, f1, 1, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> text = format_tables(EvaluationResult(rows=tuple(rows), settings={"matchers": ["planar"], "variants": ["T4"]}))
    >>> [line for line in text.splitlines() if line.startswith("Planar mean")][0]
    'Planar mean    0.75 ± 0.35'
    """
    lines = heading(result)
    for annotator in annotator_groups(result):
        who = "all annotators pooled" if annotator == POOLED else f"annotator {annotator}"
        for choice in ("oracle", "fixed", "auto"):
            header, rows, n_maps = table1(result, annotator, choice)
            if not n_maps:
                continue
            lines += ["", f"F1, {CHOICE_TITLES[choice]}, {who}, {n_maps} maps", text_table(header, rows)]
    table = orientation_table(result)
    if table is not None:
        choice = headline_choice(result)
        lines += [
            "",
            f"Mean F1 / place accuracy per orientation, {CHOICE_TITLES[choice]}, all annotators pooled",
            text_table(*table),
        ]
    human = human_lines(result) + ceiling_lines(result)
    if human:
        lines += [""] + human
    lines += [""] + comparison_lines(result)
    return "\n".join(lines) + "\n"
