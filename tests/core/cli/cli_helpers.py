"""Small maps, a correspondence file and ways to run ``ursim``, shared by the command-line tests."""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np

from ursim_core.cli import goal as goal_cli
from ursim_core.cli import route as route_cli
from ursim_core.correspondences import Clique, Correspondences, MapRef, save_correspondences
from ursim_core.errors import UrsimError


def two_rooms(path: Path, *, door: bool = True) -> Path:
    image = np.zeros((80, 170), np.uint8)
    image[5:75, 5:80] = 255
    image[5:75, 90:165] = 255
    image[35:45, 80:90] = 255 if door else 0
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), image)
    return path


def building(scale: float = 1.0) -> np.ndarray:
    """A corridor with four rooms of different sizes above and below it."""
    s = lambda v: int(round(v * scale))
    image = np.zeros((s(260), s(420)), np.uint8)
    image[s(110) : s(150), s(10) : s(410)] = 255  # corridor
    rooms = [(10, 100, 10, 140), (10, 100, 150, 400), (160, 250, 10, 250), (160, 250, 260, 330)]
    for r0, r1, c0, c1 in rooms:
        image[s(r0) : s(r1), s(c0) : s(c1)] = 255
        door = (c0 + c1) // 2
        if r1 <= 110:
            image[s(r1) : s(110), s(door - 5) : s(door + 5)] = 255
        else:
            image[s(150) : s(r0), s(door - 5) : s(door + 5)] = 255
    return image


def rooms_image(n_rooms=3, width=60, height=50, door=10):
    """White rooms in a row on black, joined by doors, so MAORIS finds n regions."""
    grey = np.zeros((height + 2, n_rooms * (width + 4) + 2), np.uint8)
    for room in range(n_rooms):
        left = 1 + room * (width + 4)
        grey[1 : height + 1, left : left + width] = 255
        if room:
            middle = height // 2
            grey[middle - door // 2 : middle + door // 2, left - 4 : left] = 255
    return grey


def correspondences_file(tmp_path, sketch, metric):
    # Rooms matched in order, by clicked points; the middle room carries a label.
    corr = Correspondences(
        sketch=MapRef(path=sketch),
        metric=MapRef(path=metric),
        cliques=(
            Clique(id=1, sketch_points=[(25, 30)], metric_points=[(35, 45)]),
            Clique(id=2, sketch_points=[(25, 95)], metric_points=[(35, 140)], extra={"label": "lab"}),
            Clique(id=3, sketch_points=[(25, 160)], metric_points=[(35, 235)]),
        ),
    )
    save_correspondences(corr, tmp_path / "corr.json")
    return tmp_path / "corr.json"


def run_cli(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ursim_core.cli", *args], capture_output=True, text=True)


def run_python(code: str, **environment: str) -> dict:
    env = {**os.environ, **environment}
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env)
    return json.loads(result.stdout.strip().splitlines()[-1])


def ursim(argv) -> int:
    """What `ursim` does once the lead registers the two commands: parse, run, one-line errors."""
    parser = argparse.ArgumentParser(prog="ursim")
    commands = parser.add_subparsers(dest="command", required=True)
    goal_cli.add_parser(commands)
    route_cli.add_parser(commands)
    args = parser.parse_args(argv)
    try:
        return args.handler(args)
    except UrsimError as error:
        print(f"error: {error}")
        return 1
