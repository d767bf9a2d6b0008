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
from ursim_core.io.map_saver import save_map_yaml
from ursim_core.io.maps import load_map


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


def building_pair(folder: Path) -> tuple[Path, Path]:
    """``sketch.png`` (:func:`building` at 1.3 times the size) and ``metric.png`` in ``folder``."""
    sketch, metric = folder / "sketch.png", folder / "metric.png"
    cv2.imwrite(str(metric), building())
    cv2.imwrite(str(sketch), building(1.3))
    return sketch, metric


def navigation_maps(folder: Path) -> tuple[Path, Path, Path]:
    """A three-room sketch, a larger metric map of the same rooms, and that map as a ROS YAML map
    (0.05 m per pixel, origin (-1, 2)) in ``folder``."""
    sketch = folder / "sketch.png"
    cv2.imwrite(str(sketch), rooms_image())
    metric_png = folder / "metric.png"
    cv2.imwrite(str(metric_png), rooms_image(width=90, height=70))
    metric_yaml = folder / "metric.yaml"
    save_map_yaml(load_map(metric_png), metric_yaml, resolution=0.05, origin=(-1.0, 2.0, 0.0))
    return sketch, metric_png, metric_yaml


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
    """``ursim goal`` and ``ursim route`` as the ``ursim`` command runs them (parse, run, one-line
    errors), on a parser of their own: what their ``add_parser`` registers."""
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
