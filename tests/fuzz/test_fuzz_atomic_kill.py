"""kill -9 during atomic saves: the target is always one complete version, never a mix.

A child process saves two alternating versions of a file in a loop through
``atomic_write_bytes`` (and ``save_correspondences``); the parent kills it with SIGKILL at
random moments. After every kill the file must read back as one of the two versions, and the
temporary files the killed writers leave are removed by the next save once they are stale.
"""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from ursim_core.correspondences import load_correspondences
from ursim_core.io.atomic import STALE_TEMP_SECONDS, atomic_write_bytes

pytestmark = [
    pytest.mark.slow,
    pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL is POSIX"),
]

WRITER = textwrap.dedent(
    """
    import sys
    from pathlib import Path
    from ursim_core.io.atomic import atomic_write_bytes
    from ursim_core.correspondences import Clique, Correspondences, save_correspondences

    target, kind = Path(sys.argv[1]), sys.argv[2]
    versions = [bytes([65 + n]) * 2_000_000 for n in range(2)]
    corrs = [Correspondences(cliques=tuple(Clique(id=i + 1, sketch_points=[(n, i)]) for i in range(3000)))
             for n in range(2)]
    print("ready", flush=True)
    n = 0
    while True:
        if kind == "bytes":
            atomic_write_bytes(target, versions[n % 2])
        else:
            save_correspondences(corrs[n % 2], target, now="2024-01-01T00:00:00Z")
        n += 1
    """
)


def _kill_loop(tmp_path, kind: str, kills: int) -> list[bytes]:
    target = tmp_path / ("data.bin" if kind == "bytes" else "pair.json")
    generator = random.Random(12)
    seen = []
    for _ in range(kills):
        child = subprocess.Popen([sys.executable, "-c", WRITER, str(target), kind], stdout=subprocess.PIPE, text=True)
        try:
            assert child.stdout.readline().strip() == "ready"
            time.sleep(generator.uniform(0.0, 0.25))
        finally:
            child.send_signal(signal.SIGKILL)
            child.wait()
            child.stdout.close()
        if target.exists():
            seen.append(target.read_bytes())
    return seen


def test_kill_9_during_byte_saves_leaves_one_whole_version(tmp_path):
    seen = _kill_loop(tmp_path, "bytes", kills=15)
    assert seen, "the writer never completed a save"
    versions = {bytes([65 + n]) * 2_000_000 for n in range(2)}
    assert all(content in versions for content in seen)
    # The killed writers' temporary files are cleaned by the next save once stale.
    leftovers = [entry for entry in tmp_path.iterdir() if entry.name.endswith(".tmp")]
    old = time.time() - STALE_TEMP_SECONDS - 1
    for entry in leftovers:
        os.utime(entry, (old, old))
    atomic_write_bytes(tmp_path / "data.bin", b"final")
    assert sorted(entry.name for entry in tmp_path.iterdir()) == ["data.bin"]


def test_kill_9_during_correspondence_saves_leaves_a_loadable_file(tmp_path):
    _kill_loop(tmp_path, "json", kills=10)
    target = tmp_path / "pair.json"
    if target.exists():
        corr = load_correspondences(target)
        assert len(corr.cliques) == 3000
        assert {clique.sketch_points[0][0] for clique in corr.cliques} in ({0}, {1})
