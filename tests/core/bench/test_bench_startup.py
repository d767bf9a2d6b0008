"""The start-up table of ``ursim bench startup`` (ursim_core.bench.startup; figures printed, never asserted)."""

from __future__ import annotations

from ursim_core.bench.startup import print_startup


def test_startup_table_states_each_target(capsys):
    print_startup(
        [
            {"case": "ursim --help", "median_s": 0.1, "min_s": 0.09, "n": 5, "target_s": 0.15},
            {"case": "ursim match (KTH 00 vs model)", "median_s": 1.0, "min_s": 0.9, "n": 5, "target_s": 0.5},
        ]
    )
    out = capsys.readouterr().out
    assert "meets target" in out and "2.0x over target" in out
