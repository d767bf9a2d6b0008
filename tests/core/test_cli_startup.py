"""What an ``ursim`` process loads and does around its command (start-up and exit; no timings)."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
from test_cli import two_rooms

from ursim_core.cli.common import progress_bar, staged_folder
from ursim_core.io import atomic

# Modules the segment path has no use for (numba is left out: it compiles the kernels when
# they are not built yet). networkx: the regions are written from their table.
NOT_ON_THE_SEGMENT_PATH = (
    "PIL", "tqdm", "scipy", "skimage", "matplotlib", "jsonschema", "multiprocessing", "networkx",
)  # fmt: skip


def run_python(code: str, **environment: str) -> dict:
    env = {**os.environ, **environment}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_segment_loads_none_of_the_libraries_it_does_not_need(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    code = (
        "import json, sys; from ursim_core.cli import main; "
        f"code = main(['segment', {str(source)!r}, '--preset', 'default', '-o', {str(tmp_path / 'out')!r}]); "
        f"print(json.dumps([code, sorted(m for m in {NOT_ON_THE_SEGMENT_PATH!r} if m in sys.modules)]))"
    )
    assert run_python(code) == [0, []]


def test_match_writes_and_reads_valid_files_without_importing_jsonschema(tmp_path):
    # The schema's validator is built only to describe a file that the direct checks refuse.
    source = two_rooms(tmp_path / "rooms.png")
    out = tmp_path / "out"
    code = (
        "import json, sys; from ursim_core.cli import main; "
        "from ursim_core.correspondences import load_correspondences; "
        f"code = main(['match', {str(source)!r}, {str(source)!r}, '-o', {str(out)!r}]); "
        f"load_correspondences({str(out / 'correspondences.json')!r}); "
        "print(json.dumps([code, 'jsonschema' in sys.modules]))"
    )
    assert run_python(code) == [0, False]


def test_the_command_line_freezes_the_heap_before_exit_and_a_caller_keeps_collecting(tmp_path):
    source = two_rooms(tmp_path / "rooms.png")
    args = ["segment", str(source), "--preset", "default", "-o", str(tmp_path / "out")]
    code = (
        "import gc, json, sys; from ursim_core.cli import main; "
        f"sys.argv = ['ursim', *{args!r}]; frozen = {{}}; "
        f"main({args!r}); frozen['argv'] = gc.get_freeze_count(); "
        "main(); frozen['command line'] = gc.get_freeze_count(); print(json.dumps(frozen))"
    )
    frozen = run_python(code)
    assert frozen["argv"] == 0 and frozen["command line"] > 0
    assert (tmp_path / "out" / "rooms.labels.png").is_file()


def test_openblas_threads_are_told_to_sleep_unless_the_user_said_otherwise():
    code = (
        "import json, os; from ursim_core.cli import main; main(['segment', '--preset', 'nope']); "
        "print(json.dumps(os.environ.get('OPENBLAS_THREAD_TIMEOUT')))"
    )
    environment = {key: value for key, value in os.environ.items() if key != "OPENBLAS_THREAD_TIMEOUT"}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=environment)
    assert result.stdout.strip().splitlines()[-1] == '"4"'
    assert run_python(code, OPENBLAS_THREAD_TIMEOUT="12") == "12"


def test_progress_bar_off_a_terminal_is_silent_and_does_not_import_tqdm(capsys):
    update = progress_bar(3, "segment")  # pytest's captured stderr is not a terminal
    update(1, text="a.png")
    update(2, 5)
    update.close()
    assert capsys.readouterr().err == ""
    code = "import json, sys; from ursim_core.cli.common import progress_bar; progress_bar(2, 'x')(2); print(json.dumps('tqdm' in sys.modules))"
    assert run_python(code) is False


def _count_directory_syncs(monkeypatch) -> list[str]:
    synced: list[str] = []
    real_fsync = os.fsync

    def fsync(descriptor):
        if stat.S_ISDIR(os.fstat(descriptor).st_mode):
            synced.append(os.readlink(f"/proc/self/fd/{descriptor}"))
        return real_fsync(descriptor)

    monkeypatch.setattr(os, "fsync", fsync)
    return synced


def test_saves_into_a_scratch_folder_sync_their_content_but_not_the_folder(tmp_path, monkeypatch):
    if not Path("/proc/self/fd").is_dir():
        pytest.skip("reads the synced folders' paths from /proc (Linux)")
    synced = _count_directory_syncs(monkeypatch)
    with atomic.scratch_directory(tmp_path):
        atomic.atomic_write_bytes(tmp_path / "a.bin", b"a")
    assert synced == []
    atomic.atomic_write_bytes(tmp_path / "b.bin", b"b")
    assert synced == [str(tmp_path)]
    assert (tmp_path / "a.bin").read_bytes() == b"a" and atomic._scratch == {}


def test_staged_outputs_sync_their_final_folder_once(tmp_path, monkeypatch):
    if not Path("/proc/self/fd").is_dir():
        pytest.skip("reads the synced folders' paths from /proc (Linux)")
    synced = _count_directory_syncs(monkeypatch)
    out = tmp_path / "out"
    with staged_folder(out) as staging:
        for name in ("a.png", "b.png", "c.json"):
            atomic.atomic_write_bytes(staging / name, name.encode())
    assert synced == [str(out)]
    assert sorted(path.name for path in tmp_path.iterdir()) == ["out"]
    assert sorted(path.name for path in out.iterdir()) == ["a.png", "b.png", "c.json"]
