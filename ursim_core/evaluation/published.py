"""Published figures quoted beside an evaluation for comparison, each constant with its source."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ursim_core.evaluation.formatting import MATCHER_NAMES, VARIANT_NAMES, markdown_table, mean_sd, number
from ursim_core.evaluation.results import VARIANTS

__all__ = [
    "PAPER_TABLE1",
    "PAPER_HUMAN_VS_HUMAN",
    "PAPER_FIXED_M",
    "PAPER_E5",
    "RELEASED_KTH",
    "RELEASED_BASELINES",
    "RELEASED_E5",
    "comparison_lines",
    "published_markdown",
]

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


def _paper_table1(variants: Sequence[str], matchers: Sequence[str]) -> tuple[list[str], list[list[str]]]:
    header = ["matcher"] + [VARIANT_NAMES.get(v, v) for v in variants]
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
                    cells.append(number(value))
                else:
                    cells.append(mean_sd(*value))
            rows.append([f"{MATCHER_NAMES.get(matcher, matcher)} {stat}"] + cells)
    return header, rows


def comparison_lines(result) -> list[str]:
    scoring = result.settings.get("scoring", "correct")
    released = RELEASED_KTH["as-built" if scoring == "as-built" else "fnfix"]
    label = "as-built" if scoring == "as-built" else "fnfix"
    lines = [
        "Published figures (other segmentation, data or scoring: compare trends, not decimals):",
        f"  paper Table 1, planar T4 (oracle m over 0..1, 25 sketches): median {PAPER_TABLE1['planar']['median']['T4']:.2f}, "
        f"mean {mean_sd(*PAPER_TABLE1['planar']['mean']['T4'])}; fixed m = {PAPER_FIXED_M['m']}: "
        f"median {PAPER_FIXED_M['median']:.2f}, mean {PAPER_FIXED_M['mean']:.2f}; human vs human: "
        f"median {PAPER_HUMAN_VS_HUMAN['median']:.2f}, mean {mean_sd(PAPER_HUMAN_VS_HUMAN['mean'], PAPER_HUMAN_VS_HUMAN['sd'])}",
        f"  released C++ on these 18 KTH sketches, planar T4, {label} scoring: oracle mean/median "
        + ", ".join(f"{a} {v[0]:.3f}/{v[1]:.3f}" for a, v in released["oracle"].items())
        + "; best fixed m "
        + ", ".join(f"{a} m={v[0]:g} mean {v[1]:.3f}" for a, v in released["fixed"].items()),
    ]
    return lines


def published_markdown(result) -> list[str]:

    header, rows = _paper_table1(VARIANTS, ("hungarian", "vf2", "planar"))
    lines = [
        "Mielle et al. 2019, Table 1 (25 KTH sketches, both annotators, oracle m over 0 .. 1 step 0.025;",
        "scoring as implemented by the released code; segmentation as the released driver):",
        "",
        markdown_table(header, rows),
        "",
        f"- Fixed m for all sketches (Section 6.4): best around m = {PAPER_FIXED_M['m']}, median {PAPER_FIXED_M['median']:.2f}, mean {PAPER_FIXED_M['mean']:.2f}.",
        f"- Human vs human: median {PAPER_HUMAN_VS_HUMAN['median']:.2f}, mean {mean_sd(PAPER_HUMAN_VS_HUMAN['mean'], PAPER_HUMAN_VS_HUMAN['sd'])}.",
        "- Halmstad E5 (Table 2), median / mean ± sd: "
        + "; ".join(f"{name} {v[0]:.2f} / {mean_sd(v[1], v[2])}" for name, v in PAPER_E5.items())
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
        markdown_table(
            ["scoring", "annotator", "oracle median", "oracle mean", "best fixed m", "fixed median", "fixed mean"],
            table_rows,
        ),
        "",
        "- Baselines on all 26 sketches (fnfix, mean F1 malcolm / vasiliki): "
        + "; ".join(f"{MATCHER_NAMES[k]} {v[0]:.3f} / {v[1]:.3f}" for k, v in RELEASED_BASELINES.items())
        + ".",
        "- Halmstad E5 (fnfix, mean F1 malcolm / vasiliki): "
        + "; ".join(f"{k} {v[0]:.3f} / {v[1]:.3f}" for k, v in RELEASED_E5.items())
        + ".",
        "",
    ]
    return lines
