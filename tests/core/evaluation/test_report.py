"""Report writing: runs.csv, Table-1-style text, summary.md and the PNG plots, from hand-made rows."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest
from PIL import Image

from ursim_core.evaluation.plots import plot_boxplots, plot_f1_vs_m
from ursim_core.evaluation.published import PAPER_TABLE1, RELEASED_KTH
from ursim_core.evaluation.report import markdown_summary, runs_csv, write_report
from ursim_core.evaluation.results import RUN_COLUMNS, EvaluationResult, RunRow, m_label
from ursim_core.evaluation.tables import format_tables

MATCHERS = ("planar", "hungarian")
VARIANTS = ("T4", "baseline")
GRID = (0.0, 0.1, 0.2)


def _f1(name: str, annotator: str, matcher: str, variant: str, m: float) -> float:
    """A deterministic F1 with a known best m: planar T4 peaks at m = 0.1 for every map."""
    base = {"00": 0.6, "01": 0.8, "02": 0.4}[name] - (0.1 if annotator == "vasiliki" else 0.0)
    if matcher == "planar" and variant == "T4":
        return round(base if m == 0.1 else base / 2, 6)
    return round(base / 4, 6)


def _result(*, human: bool = True) -> EvaluationResult:
    rows = []
    for name in ("00", "01", "02"):
        for annotator in ("malcolm", "vasiliki"):
            for matcher in MATCHERS:
                for variant in VARIANTS:
                    for m in (*GRID, "auto"):
                        value = 0.1 if m == "auto" else m
                        f1 = _f1(name, annotator, matcher, variant, value)
                        rows.append(
                            RunRow(
                                map=name,
                                annotator=annotator,
                                matcher=matcher,
                                variant=variant,
                                m_label="auto" if m == "auto" else m_label(m),
                                m_value=value,
                                tp=2,
                                fp=1,
                                fn=1,
                                precision=f1,
                                recall=f1,
                                f1=f1,
                                seeds=4,
                                n_sketch_regions=5,
                                n_metric_regions=6,
                                time_s=0.002,
                                model="model_simple",
                                n_pairs=3,
                                reason="" if value else "no seeds: no pair of regions has c <= m = 0",
                            )
                        )
    human_rows = []
    if human:
        for name, f1 in (("00", 1.0), ("01", 0.8), ("02", 0.6)):
            for reference, scored in (("malcolm", "vasiliki"), ("vasiliki", "malcolm")):
                human_rows.append(
                    RunRow(
                        name,
                        reference,
                        "human",
                        scored,
                        "-",
                        math.nan,
                        2,
                        0,
                        1,
                        1.0,
                        2 / 3,
                        f1,
                        0,
                        5,
                        6,
                        0.0,
                        "model_simple",
                        2,
                    )
                )
    settings = {
        "dataset": "/data/kth",
        "matchers": list(MATCHERS),
        "variants": list(VARIANTS),
        "m_grid": list(GRID),
        "auto_m": True,
        "presets_used": ["robot", "sketch"],
        "scoring": "correct",
        "workers": 2,
        "n_experiments": 3,
        "config": {"rotation_search": "min"},
    }
    timings = {"segmentation_s": 1.5, "matching_s": 2.5, "total_s": 4.0, "maps": 4, "maps_from_cache": 1}
    return EvaluationResult(
        rows=tuple(rows),
        human_rows=tuple(human_rows),
        settings=settings,
        timings=timings,
        notes=("01 (malcolm): 1 ground-truth point(s) more than 10 px from any region, dropped",),
    )


@pytest.fixture(scope="module")
def result() -> EvaluationResult:
    return _result()


def test_csv_has_the_columns_and_one_line_per_run(result):
    parsed = list(csv.DictReader(io.StringIO(runs_csv(result))))
    assert tuple(parsed[0]) == RUN_COLUMNS
    assert RUN_COLUMNS[:16] == (
        "map",
        "annotator",
        "matcher",
        "variant",
        "m_label",
        "m_value",
        "tp",
        "fp",
        "fn",
        "precision",
        "recall",
        "f1",
        "seeds",
        "n_sketch_regions",
        "n_metric_regions",
        "time_s",
    )
    assert len(parsed) == len(result.rows) + len(result.human_rows)
    first = parsed[0]
    assert (first["map"], first["annotator"], first["matcher"], first["variant"], first["m_label"]) == (
        "00",
        "malcolm",
        "planar",
        "T4",
        "0",
    )
    assert float(first["f1"]) == pytest.approx(0.3)
    human = [line for line in parsed if line["matcher"] == "human"]
    assert len(human) == 6 and human[0]["m_value"] == "" and human[0]["variant"] == "vasiliki"


def test_text_tables_are_table_1_style(result):
    text = format_tables(result)
    lines = text.splitlines()
    # Columns in the paper's order whatever order the variants were run in.
    header = next(line for line in lines if line.startswith("matcher"))
    assert header.split() == ["matcher", "Baseline", "T4"]
    assert "F1, oracle m (best m of the grid for each map), annotator malcolm, 3 maps" in text
    assert "all annotators pooled, 6 maps" in text
    # malcolm, planar T4 oracle: F1 0.6, 0.8, 0.4 -> median 0.60, mean 0.60 +- 0.20.
    oracle_block = text.split("F1, oracle m (best m of the grid for each map), annotator malcolm")[1].split("\n\n")[0]
    planar_mean = next(line for line in oracle_block.splitlines() if line.startswith("Planar mean"))
    assert planar_mean.split()[-3:] == ["0.60", "±", "0.20"]
    fixed_block = text.split("F1, best single fixed m (highest mean F1 over the maps), annotator malcolm")[1].split(
        "\n\n"
    )[0]
    best_m = next(line for line in fixed_block.splitlines() if line.startswith("Planar best m"))
    assert best_m.split()[-1] == "0.1"
    assert (
        "Human vs human (vasiliki's cliques scored against malcolm's): F1 median 0.80, mean 0.80 ± 0.20; "
        "place accuracy mean - (3 maps)" in text
    )
    assert "0.568/0.633" in text  # the released code's oracle, fnfix, malcolm (mean/median)
    assert "time: segmentation 1.5 s" in text


def test_legacy_scoring_compares_with_the_as_built_figures():
    legacy = _result()
    legacy.settings["scoring"] = "as-built"
    text = format_tables(legacy)
    mean, median = RELEASED_KTH["as-built"]["oracle"]["malcolm"]
    assert f"{mean:.3f}/{median:.3f}" in text and "as-built scoring" in text


def test_markdown_summary_has_tables_human_line_published_figures_and_notes(result):
    text = markdown_summary(result)
    assert text.startswith("# URSIM evaluation")
    assert "| matcher | Baseline | T4 |" in text
    assert "| Planar median | 0.15 | 0.60 |" in text  # baseline: F1 / 4 = 0.15, 0.2, 0.1; T4: 0.6, 0.8, 0.4
    assert "| Planar best m | 0 | 0.1 |" in text
    assert "## Human vs human" in text
    assert "## Mean F1 for each fixed m" in text and "| 0.1 |" in text
    paper_planar_t4 = PAPER_TABLE1["planar"]["median"]["T4"]
    assert (
        f"| Planar median | {PAPER_TABLE1['planar']['median']['baseline']:.2f}" in text
        and f"{paper_planar_t4:.2f}" in text
    )
    assert "dropped" in text  # the notes
    assert "no seeds: no pair of regions has c <= m = ..." in text  # degenerate runs grouped


def test_plots_of_an_empty_result_still_render():
    empty = EvaluationResult()
    for maker in (plot_f1_vs_m, plot_boxplots):
        with Image.open(io.BytesIO(maker(empty))) as image:
            assert image.format == "PNG"


def test_write_report_writes_the_four_files_atomically(result, tmp_path):
    out = tmp_path / "report" / "nested"
    written = write_report(result, out)
    assert sorted(written) == ["boxplots.png", "f1_vs_m.png", "place_vs_m.png", "runs.csv", "summary.md"]
    for name, path in written.items():
        assert path == out / name and path.stat().st_size > 100
    assert (out / "runs.csv").read_text() == runs_csv(result)
    assert (out / "summary.md").read_text(encoding="utf-8") == markdown_summary(result)
    with Image.open(out / "place_vs_m.png") as image:
        assert image.format == "PNG"  # these hand-made rows have no place accuracy to plot
    for name in ("f1_vs_m.png", "boxplots.png"):
        with Image.open(out / name) as image:
            assert image.format == "PNG"
            assert image.width > 400 and image.height > 300
            # Not a blank canvas: lines, boxes and text in several greys and colours.
            assert len(np.unique(np.asarray(image.convert("L")))) > 10
    # No temporary file left behind; a second write replaces the files.
    write_report(_result(human=False), out)
    assert sorted(p.name for p in out.iterdir()) == sorted(written)
    assert "human" not in (out / "runs.csv").read_text()
