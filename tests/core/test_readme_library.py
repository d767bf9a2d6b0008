"""The README's library example runs as written, on the bundled example pair."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _example_code() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.index("## The library: from sketch to goal in Python")
    start = text.index("```python\n", section) + len("```python\n")
    return text[start : text.index("```", start)]


def test_the_readme_library_example_runs_and_matches_the_example_pair(tmp_path, monkeypatch):
    (tmp_path / "resources").symlink_to(ROOT / "resources")
    monkeypatch.chdir(tmp_path)
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        exec(compile(_example_code(), "README.md", "exec"), {"__name__": "readme_example"})
    lines = printed.getvalue().splitlines()
    assert len(lines) == 3
    assert lines[2] == "1.0 1.0"  # pair F1 and place accuracy against the example's ground truth
    assert (tmp_path / "pair.json").is_file()
