"""Whole-process start-up timings: what a user waits for when running ``ursim`` from a shell.

Each command is run ``repeats`` times as a fresh process (after one warm-up run, so the OS file
cache, Python's bytecode cache and the kernels are warm) and the median wall time is printed beside its target
(issue 10 item 4): ``ursim --help`` <= 0.15 s, ``ursim match`` of a KTH pair <= 0.5 s, and
faster than the authors' C++ MAORIS, which took 1.04 s as a whole process on the KTH model map.
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["STARTUP_TARGETS", "bench_startup", "print_startup"]

#: Target whole-process seconds by case (None: no target, printed for reference).
STARTUP_TARGETS: dict[str, float | None] = {
    "python -c pass": None,
    "ursim --help": 0.15,
    "ursim match (KTH 00 vs model)": 0.5,
    "ursim match (KTH 00 turned 30 deg)": None,
    "ursim segment (KTH model)": 1.04,
}
_TARGET_NOTES = {
    "ursim segment (KTH model)": "the authors' C++ MAORIS, whole process",
}


def _ursim_command() -> list[str]:
    script = Path(sys.executable).with_name("ursim")
    return [str(script)] if script.is_file() else [sys.executable, "-m", "ursim_core.cli"]


def _environment() -> dict[str, str]:
    """This process's environment with Python's bytecode cache allowed.

    A user's Python writes ``__pycache__`` on the first run and reads it afterwards; with
    ``PYTHONDONTWRITEBYTECODE`` set (some CI and sandbox shells) every run would compile the
    project's ~150 modules again, about 0.1 s that no user waits for.
    """
    environment = dict(os.environ)
    environment.pop("PYTHONDONTWRITEBYTECODE", None)
    return environment


def _time(command: list[str], repeats: int) -> list[float]:
    environment = _environment()
    subprocess.run(command, check=True, capture_output=True, env=environment)  # warm-up
    times = []
    for _ in range(repeats):
        started = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True, env=environment)
        times.append(time.perf_counter() - started)
    return times


def bench_startup(kth: Path | None, *, repeats: int = 5) -> list[dict]:
    """Median whole-process seconds of each case; the KTH cases are left out when ``kth`` is None."""
    ursim = _ursim_command()
    cases: list[tuple[str, list[str]]] = [("python -c pass", [sys.executable, "-c", "pass"])]
    cases.append(("ursim --help", [*ursim, "--help"]))
    out = Path(tempfile.mkdtemp(prefix="ursim-bench-startup-"))
    try:
        if kth is not None:
            model = kth / "model" / "model_simple.png"
            sketch = kth / "sketches" / "00.png"
            cases.append(
                ("ursim match (KTH 00 vs model)", [*ursim, "match", str(sketch), str(model), "-o", str(out / "m")])
            )
            # A sketch drawn at an angle: segmented in six resamplings, which the matcher votes over.
            turned = out / "00_turned_30.png"
            _write_turned(sketch, turned, 30.0)
            cases.append(
                ("ursim match (KTH 00 turned 30 deg)", [*ursim, "match", str(turned), str(model), "-o", str(out / "t")])
            )
            cases.append(
                (
                    "ursim segment (KTH model)",
                    [*ursim, "segment", str(model), "--preset", "default", "-o", str(out / "s")],
                )
            )
        rows = []
        for name, command in cases:
            times = _time(command, repeats)
            rows.append(
                {
                    "case": name,
                    "median_s": statistics.median(times),
                    "min_s": min(times),
                    "n": len(times),
                    "target_s": STARTUP_TARGETS.get(name),
                }
            )
        return rows
    finally:
        shutil.rmtree(out, ignore_errors=True)


def _write_turned(source: Path, target: Path, degrees: float) -> None:
    """The map image ``source`` turned by ``degrees`` on a canvas that holds it, as a PNG at ``target``."""
    import cv2

    from ursim_core.evaluation.augment import Orientation, transform_image
    from ursim_core.io.maps import load_map

    free = transform_image(load_map(source).free, Orientation(degrees))
    if not cv2.imwrite(str(target), free.astype("uint8") * 255):
        raise OSError(f"{target}: could not write the turned sketch")


def print_startup(rows: list[dict]) -> None:
    print(f"{'case':<36} {'median s':>9} {'min s':>7} {'target s':>9}  verdict")
    for row in rows:
        target = row["target_s"]
        if target is None:
            verdict, target_text = "(reference)", "-"
        else:
            verdict = "meets target" if row["median_s"] <= target else f"{row['median_s'] / target:.1f}x over target"
            target_text = f"{target:.2f}"
            if row["case"] in _TARGET_NOTES:
                verdict += f" ({_TARGET_NOTES[row['case']]})"
        print(f"{row['case']:<36} {row['median_s']:>9.3f} {row['min_s']:>7.3f} {target_text:>9}  {verdict}")
    print(f"(median of {rows[0]['n'] if rows else 0} fresh processes after one warm-up run)")


#: The released C++ MAORIS on the KTH maps with its library defaults (t 0.25, doors 40), wall
#: seconds per map as measured in ../shared/design/released_code_results.md ("MAORIS region counts
#: and times per map", column default_t025). The C++ figures are the segmentation alone, so a
#: whole ``ursim segment`` process that beats them beats the C++ process by more.
RELEASED_MAORIS_S = {
    "00": 1.42, "01": 1.46, "03": 0.38, "04": 1.11, "06": 0.53, "07": 0.56, "08": 0.66, "10": 0.67,
    "11": 0.26, "12": 6.29, "14": 0.34, "15": 0.79, "17": 1.66, "18": 13.54, "20": 8.71, "21": 7.56,
    "23": 5.76, "24": 30.10, "model_simple": 0.71,
}  # fmt: skip


def bench_segment_processes(kth: Path, *, repeats: int = 3) -> list[dict]:
    """Whole ``ursim segment --preset default`` processes on every KTH map beside the C++ figure."""
    ursim = _ursim_command()
    out = Path(tempfile.mkdtemp(prefix="ursim-bench-maps-"))
    try:
        paths = sorted((kth / "sketches").glob("*.png")) + [kth / "model" / "model_simple.png"]
        rows = []
        for path in paths:
            if path.stem not in RELEASED_MAORIS_S:
                continue
            command = [*ursim, "segment", str(path), "--preset", "default", "-o", str(out / path.stem)]
            times = _time(command, repeats)
            rows.append({"map": path.stem, "median_s": statistics.median(times), "cpp_s": RELEASED_MAORIS_S[path.stem]})
        return rows
    finally:
        shutil.rmtree(out, ignore_errors=True)


def print_segment_processes(rows: list[dict]) -> None:
    print(f"{'map':<14} {'ursim segment s':>15} {'C++ MAORIS s':>13}  ratio")
    for row in rows:
        print(f"{row['map']:<14} {row['median_s']:>15.3f} {row['cpp_s']:>13.2f}  {row['cpp_s'] / row['median_s']:.1f}x")
    slowest = min(rows, key=lambda row: row["cpp_s"] / row["median_s"]) if rows else None
    if slowest is not None:
        verdict = "faster on every map" if all(r["median_s"] < r["cpp_s"] for r in rows) else "NOT faster on every map"
        print(f"{verdict}; closest: {slowest['map']} ({slowest['cpp_s'] / slowest['median_s']:.1f}x)")
