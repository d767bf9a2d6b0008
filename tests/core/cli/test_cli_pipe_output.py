"""``-o /dev/stdout`` into a pipe (``ursim goal ... -o /dev/stdout | jq``): the file is written through
the pipe (ursim_core.io.atomic), not refused as a named pipe, and never replaced by a plain file."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest
from cli_helpers import navigation_maps


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/dev/stdout of a pipe as on Linux")
def test_goal_writes_its_file_to_standard_output_when_it_is_a_pipe(tmp_path):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    argv = ["goal", str(sketch), str(metric_yaml), "--at", "25,30", "-o", "/dev/stdout"]
    # Captured: standard output is a pipe, as under `| cat`; the timeout keeps a hang from
    # stopping the suite.
    result = subprocess.run([sys.executable, "-m", "ursim_core.cli", *argv], capture_output=True, timeout=300)
    assert result.returncode == 0, result.stderr.decode()
    # Once: -o is standard output, so the JSON is not printed a second time (jq would read two
    # documents).
    assert json.loads(result.stdout.decode())["header"]["frame_id"] == "map"
