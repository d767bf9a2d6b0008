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
