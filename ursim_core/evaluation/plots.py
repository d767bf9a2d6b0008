"""Plots of an evaluation as PNG bytes (matplotlib, Agg): F1 against m, F1 distributions."""

from __future__ import annotations

import io

from ursim_core.evaluation.formatting import CHOICE_TITLES, MATCHER_NAMES, VARIANT_NAMES
from ursim_core.evaluation.results import POOLED, mean_f1_by_m
from ursim_core.evaluation.tables import annotator_groups, methods

__all__ = ["plot_f1_vs_m", "plot_place_vs_m", "plot_boxplots"]


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


def plot_place_vs_m(result) -> bytes:
    """PNG of mean place accuracy against m, laid out as :func:`plot_f1_vs_m`."""
    return plot_f1_vs_m(result, value="place_accuracy")


def plot_f1_vs_m(result, *, value: str = "f1") -> bytes:
    """PNG of mean F1 against m: one panel per matcher x annotator, one line per variant.

    The mean F1 with the automatic m is drawn as a dashed horizontal line of the variant's colour.

    Examples
    --------
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> rows = [RunRow("00", "a", "planar", "T4", label, m, 1, 0, 0, 1.0, 1.0, m, 1, 3, 3, 0.0)
    ...         for label, m in (("0", 0.0), ("0.1", 0.1))]
    >>> plot_f1_vs_m(EvaluationResult(rows=tuple(rows)))[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
    True
    """

    plt = _pyplot()
    by_m = mean_f1_by_m(result.rows, value=value)
    what = "place accuracy" if value == "place_accuracy" else "F1"
    matchers, variants = methods(result)
    annotators = [a for a in annotator_groups(result) if a != POOLED]
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
                        label=VARIANT_NAMES.get(variant, variant),
                    )
                auto = result.summary(annotator, matcher, variant, "auto")
                auto_value = (
                    None
                    if auto is None or not auto.n
                    else (auto.mean_place if value == "place_accuracy" else auto.mean)
                )
                if auto_value is not None and auto_value == auto_value:  # not NaN
                    axis.axhline(auto_value, color=colour, linestyle="--", linewidth=1)
            axis.set_title(f"{MATCHER_NAMES.get(matcher, matcher)}, {annotator}", fontsize=10)
            axis.set_ylim(0, 1.02)
            axis.grid(alpha=0.3)
            if row_index == len(matchers) - 1:
                axis.set_xlabel("m")
            if col_index == 0:
                axis.set_ylabel(f"mean {what} over maps")
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
    >>> from ursim_core.evaluation.results import EvaluationResult, RunRow
    >>> rows = [RunRow(name, "a", "planar", "T4", "0.1", 0.1, 1, 0, 0, 1.0, 1.0, f1, 1, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> plot_boxplots(EvaluationResult(rows=tuple(rows)))[:4] == b"\\x89PNG"
    True
    """

    plt = _pyplot()
    matchers, variants = methods(result)
    annotators = [a for a in annotator_groups(result) if a != POOLED]
    choices = [c for c in ("oracle", "fixed", "auto") if any(s.choice == c for s in result.summaries)]
    if not choices or not annotators:
        return _empty_plot(plt, "no runs to plot")
    colours = plt.get_cmap("Set2")
    method_pairs = [(m, v) for m in matchers for v in variants]
    humans = list(result.human_summaries)
    width = 0.8 / len(annotators)
    figure, axes = plt.subplots(
        len(choices),
        1,
        figsize=(
            max(7.0, 0.75 * (len(method_pairs) + len(humans)) * max(1, len(annotators)) ** 0.5 + 2),
            3.2 * len(choices),
        ),
        squeeze=False,
        sharey=True,
    )
    tick_labels = [f"{MATCHER_NAMES.get(m, m)}\n{VARIANT_NAMES.get(v, v)}" for m, v in method_pairs]
    tick_labels += [f"human\n{h.variant} vs {h.annotator}" for h in humans]
    for axis, choice in zip((row[0] for row in axes), choices):
        for annotator_index, annotator in enumerate(annotators):
            data, positions = [], []
            for method_index, (matcher, variant) in enumerate(method_pairs):
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
            positions = [len(method_pairs) + i for i in range(len(humans))]
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
        axis.set_title(f"F1 per map, {CHOICE_TITLES[choice]}", fontsize=10)
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
