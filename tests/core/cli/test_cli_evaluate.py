"""``ursim evaluate`` (ursim_core.cli.evaluate) on the small generated dataset of conftest.py."""

from __future__ import annotations

from ursim_core.cli import main


def test_evaluate_prints_tables_and_writes_the_report(synthetic_dataset, tmp_path, capsys):
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


def test_evaluate_paper_released_and_legacy_options(synthetic_dataset, capsys):
    base = ["evaluate", str(synthetic_dataset), "--matchers", "planar", "--variants", "T4", "--workers", "1"]
    assert main(base + ["--paper"]) == 0
    assert main(base + ["--released", "--legacy-scoring", "fnfix"]) == 0
    assert "scoring legacy fnfix" in capsys.readouterr().out
    assert main(base + ["--legacy-scoring"]) == 0


def test_evaluate_bad_folder_is_an_input_error(tmp_path, capsys):
    assert main(["evaluate", str(tmp_path)]) == 1
    assert str(tmp_path) in capsys.readouterr().err


# --------------------------------------------------------------------------- --cross-validate (ursim_core.evaluation.crossval)


def test_cli_cross_validates_an_option(synthetic_dataset, tmp_path, capsys):
    report = tmp_path / "report"
    args = ["evaluate", str(synthetic_dataset), "--matchers", "planar", "--variants", "T4", "--workers", "1"]
    assert main(args + ["--cross-validate", "position_weight=0,2", "-o", str(report)]) == 0
    out = capsys.readouterr().out
    assert "Leave-one-map-out cross-validation of position_weight" in out and "held-out F1" in out
    assert (report / "crossval.md").is_file()
    assert (report / "position_weight=0" / "runs.csv").is_file() and (
        report / "position_weight=2" / "summary.md"
    ).is_file()


def test_cli_rejects_unknown_options_and_two_matchers(synthetic_dataset, capsys):
    base = ["evaluate", str(synthetic_dataset), "--variants", "T4", "--workers", "1"]
    assert main(base + ["--matchers", "planar", "--set", "no_such_option=1"]) != 0
    assert "no_such_option" in capsys.readouterr().err
    assert main(base + ["--matchers", "planar", "hungarian", "--cross-validate", "position_weight=0,2"]) != 0
    assert "one --matchers" in capsys.readouterr().err
