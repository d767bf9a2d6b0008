"""Cell and table formatting shared by the report modules (text and markdown tables, names)."""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence

__all__ = [
    "CHOICE_TITLES",
    "MATCHER_NAMES",
    "VARIANT_NAMES",
    "number",
    "mean_sd",
    "median",
    "m_text",
    "text_table",
    "markdown_table",
]

CHOICE_TITLES = {
    "oracle": "oracle m (best m of the grid for each map)",
    "fixed": "best single fixed m (highest mean F1 over the maps)",
    "auto": "automatic m",
}
MATCHER_NAMES = {"auto": "Automatic", "planar": "Planar", "hungarian": "Hungarian", "vf2": "VF2"}
VARIANT_NAMES = {"baseline": "Baseline", "T1": "T1", "T2": "T2", "T3": "T3", "T4": "T4"}


def number(value: float) -> str:
    return "-" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.2f}"


def mean_sd(mean: float, sd: float) -> str:
    if mean is None or math.isnan(mean):
        return "-"
    return f"{mean:.2f} ± {sd:.2f}" if not math.isnan(sd) else f"{mean:.2f}"


def median(values: Sequence[float]) -> float:

    values = [v for v in values if not math.isnan(v)]
    return float(statistics.median(values)) if values else math.nan


def m_text(value: float) -> str:
    return "-" if math.isnan(value) else f"{value:.3g}"


def text_table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(str(line[i])) for line in [header, *rows]) for i in range(len(header))]
    lines = []
    for line in [header, *rows]:
        lines.append("  ".join(str(cell).ljust(width) for cell, width in zip(line, widths)).rstrip())
    return "\n".join(lines)


def markdown_table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)
