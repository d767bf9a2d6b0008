"""``ursim evaluate`` through the command line on a small generated dataset."""

from __future__ import annotations

from test_evaluation import synthetic_dataset  # noqa: F401  (pytest fixture)

from ursim_core.cli import main


def test_evaluate_prints_tables_and_writes_the_report(synthetic_dataset, tmp_path, capsys):  # noqa: F811
    report = tmp_path / "report"
    args = [
        "evaluate",
        str(synthetic_dataset),
        "--matchers",
        "planar",
        "--variants",
        "T4",
        "--workers",
        "1",
        "-o",
        str(report),
    ]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "F1, oracle m" in out and "F1, automatic m" in out and "Human vs human" in out
    assert {p.name for p in report.iterdir()} >= {
        "runs.csv",
        "summary.md",
        "f1_vs_m.png",
        "place_vs_m.png",
        "boxplots.png",
    }


def test_evaluate_paper_released_and_legacy_options(synthetic_dataset, capsys):  # noqa: F811
    base = ["evaluate", str(synthetic_dataset), "--matchers", "planar", "--variants", "T4", "--workers", "1"]
    assert main(base + ["--paper"]) == 0
    assert main(base + ["--released", "--legacy-scoring", "fnfix"]) == 0
    assert "scoring legacy fnfix" in capsys.readouterr().out
    assert main(base + ["--legacy-scoring"]) == 0


def test_evaluate_bad_folder_is_an_input_error(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path)]) == 1
    assert str(tmp_path) in capsys.readouterr().err
