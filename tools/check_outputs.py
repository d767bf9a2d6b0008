"""Digest every output the CLI writes, to check that a refactor changes none of them.

    .venv/bin/python tools/check_outputs.py OUT_DIR            # writes OUT_DIR/digests.json
    .venv/bin/python tools/check_outputs.py OUT_DIR --compare OLD_DIR/digests.json

Drives only the ``ursim`` command line (its interface does not move with the code), so the
same script runs on the code before and after a change. Covers: label images of the KTH
sketches and model (presets sketch, default), the MAORIS robot maps (robot, default), generated
buildings; ``ursim match`` outputs (correspondence JSON, label images) of every KTH pair; the
``ursim evaluate`` CSV of the KTH set. Needs ../shared/datasets (or URSIM_DATASETS).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _datasets() -> Path:
    env = os.environ.get("URSIM_DATASETS")
    return Path(env) if env else ROOT.parent / "shared" / "datasets"


def _ursim(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "ursim_core.cli", *args], check=True, stdout=subprocess.DEVNULL)


def _digest(path: Path, out: Path) -> str:
    """sha256 of a file, less what is not an output: timestamps, the output folder, timings."""
    data = path.read_bytes()
    if path.suffix == ".json":
        document = json.loads(data.decode().replace(str(out), "OUT"))
        document.pop("created", None)
        document.pop("modified", None)
        data = json.dumps(document, sort_keys=True).encode()
    elif path.suffix == ".csv":
        rows = [line.split(",") for line in data.decode().splitlines()]
        if rows and "time_s" in rows[0]:
            column = rows[0].index("time_s")
            rows = [row[:column] + row[column + 1 :] for row in rows]
            # VF2 runs under a wall-clock budget, so its rows depend on the machine's load.
            matcher = rows[0].index("matcher")
            rows = [row for row in rows if row[matcher] != "vf2"]
        data = "\n".join(",".join(row) for row in rows).encode()
    return hashlib.sha256(data).hexdigest()


def produce(out: Path) -> dict[str, str]:
    data = _datasets()
    kth = data / "ursim_kth_sketches"
    sketches = sorted((kth / "sketches").glob("*.png"))
    model = kth / "model" / "model_simple.png"
    robot_maps = sorted((data / "maoris_segmentation" / "robot_maps" / "maps").glob("*.png"))
    for preset in ("sketch", "default"):
        _ursim("segment", *map(str, sketches), str(model), "--preset", preset, "-o", str(out / f"seg-kth-{preset}"))
    for preset in ("robot", "default"):
        _ursim("segment", *map(str, robot_maps), "--preset", preset, "-o", str(out / f"seg-robot-{preset}"))
    buildings = out / "buildings"
    buildings.mkdir(parents=True, exist_ok=True)
    subprocess.run(
        [
            sys.executable,
            "-c",
            (
                "import sys, numpy as np, cv2\n"
                "from ursim_core.synth import make_large_building\n"
                "for size in (600, 1000):\n"
                "    for seed in (0, 1):\n"
                "        plan = make_large_building(size, seed=seed)\n"
                "        cv2.imwrite(f'{sys.argv[1]}/b{size}_{seed}.png', plan.free.astype(np.uint8) * 255)\n"
            ),
            str(buildings),
        ],
        check=True,
    )
    _ursim("segment", *map(str, sorted(buildings.glob("*.png"))), "--preset", "robot", "-o", str(out / "seg-buildings"))
    for sketch in sketches:
        _ursim("match", str(sketch), str(model), "-o", str(out / f"match-{sketch.stem}"))
    _ursim("evaluate", str(kth), "-o", str(out / "evaluate"), "--cache", str(out / "cache"))
    return _digests(out)


def _digests(out: Path) -> dict[str, str]:
    digests = {}
    for path in sorted(out.rglob("*")):
        if (
            path.is_file()
            and path.suffix in (".png", ".json", ".csv")
            and "cache" not in path.parts
            and path.name != "digests.json"
        ):
            if path.name.endswith(".overlay.png") or (path.parent.name == "evaluate" and path.suffix == ".png"):
                continue  # figures: matplotlib and font versions, not outputs of the method
            digests[str(path.relative_to(out))] = _digest(path, out)
    return digests


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path)
    parser.add_argument("--compare", type=Path, help="digests.json of an earlier run")
    parser.add_argument("--digest-only", action="store_true", help="digest OUT as it is, run nothing")
    args = parser.parse_args()
    digests = produce(args.out) if not args.digest_only else _digests(args.out)
    (args.out / "digests.json").write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")
    print(f"{len(digests)} outputs digested into {args.out / 'digests.json'}")
    if args.compare:
        old = json.loads(args.compare.read_text())
        differ = sorted(k for k in set(old) | set(digests) if old.get(k) != digests.get(k))
        for key in differ:
            print(f"DIFFERS: {key}")
        print(f"{len(old)} old, {len(digests)} new, {len(differ)} differ")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
