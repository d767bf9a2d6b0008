"""``ursim bench`` (ursim_core.cli.bench): its options."""

from __future__ import annotations

import pytest


@pytest.mark.parametrize("option", ["--seeds", "--repeats"])
@pytest.mark.parametrize("value", ["0", "-3", "x"])
def test_counts_below_one_are_usage_errors(option, value, capsys):
    from ursim_core.cli import main

    with pytest.raises(SystemExit) as stopped:
        main(["bench", "invariance", option, value])
    assert stopped.value.code == 2
    assert "at least 1" in capsys.readouterr().err


def test_told_reaches_the_invariance_bench(monkeypatch):
    import ursim_core.bench.runner as runner
    from ursim_core.cli import main

    seen = {}
    monkeypatch.setattr(runner, "run_bench", lambda what, **options: seen.update(options, what=what) or 0)
    assert main(["bench", "invariance", "--seeds", "3", "--told"]) == 0
    assert seen["what"] == "invariance" and seen["told"] is True and seen["seeds"] == 3
    assert main(["bench", "invariance"]) == 0 and seen["told"] is False
