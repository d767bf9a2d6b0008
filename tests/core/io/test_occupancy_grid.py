"""OccupancyGrid <-> Map and the map_server writer, checked against the loader rules of nav2's map_io."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ursim_core.errors import MapError, ParameterError
from ursim_core.io.maps import load_map, map_from_array, pixel_to_world
from ursim_core.io.occupancy_grid import (
    OccupancyGrid,
    map_from_occupancy_grid,
    occupancy_grid_from_map,
    quaternion_from_yaw,
    save_map_yaml,
    yaw_from_quaternion,
)

SHAPES = [(1, 3), (7, 5), (32, 48)]
YAWS = [0.0, 0.7, -2.5, math.pi]


def random_grid(shape, seed, *, values=(-1, 0, 100), yaw=0.3) -> OccupancyGrid:
    rng = np.random.default_rng(seed)
    height, width = shape
    data = rng.choice(np.asarray(values), size=height * width)
    data[0] = 0  # at least one free cell
    return OccupancyGrid(data=data, width=width, height=height, resolution=0.05, origin=(1.5, -2.25, yaw))


def nav2_cell(grey: int, alpha: int | None, *, mode: str, negate: int, free: float, occupied: float) -> int:
    """nav2 loadMapFromFile for one 8-bit grey pixel, written out independently of ursim_core."""
    channels = [grey * 257] * 3
    if mode == "trinary" and alpha is not None:
        channels.append(alpha * 257)
    shade = (sum(channels) / len(channels)) / 65535.0
    occ = shade if negate else 1.0 - shade
    if mode == "raw":
        value = math.floor(shade * 255 + 0.5)
        return value if 0 <= value <= 100 else -1
    if mode == "scale" and alpha is not None and alpha != 255:
        return -1
    if occupied < occ:
        return 100
    if occ < free:
        return 0
    if mode == "trinary":
        return -1
    return min(max(round((occ - free) / (occupied - free) * 100.0), 1), 99)


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("yaw", YAWS)
def test_grid_to_map_to_grid_is_identity(shape, yaw):
    grid = random_grid(shape, seed=shape[0] * 31 + shape[1], values=np.arange(-1, 101), yaw=yaw)
    the_map = map_from_occupancy_grid(grid.data, grid.width, grid.height, grid.resolution, grid.origin)
    assert occupancy_grid_from_map(the_map) == grid
    # The rows are flipped: the grid's first row is the image's bottom row.
    assert np.array_equal(the_map.occupancy[-1], grid.data[: grid.width])
    assert np.array_equal(the_map.free, the_map.occupancy == 0)


def test_origin_forms_and_quaternion_to_yaw():
    qx, qy, qz, qw = quaternion_from_yaw(0.9)
    message = {
        "header": {"frame_id": "map"},
        "info": {
            "width": 2,
            "height": 1,
            "resolution": 0.1,
            "origin": {"position": {"x": 3.0, "y": 4.0, "z": 0.0}, "orientation": {"x": qx, "y": qy, "z": qz, "w": qw}},
        },
        "data": [0, 100],
    }
    grid = OccupancyGrid.from_message(message)
    assert grid.origin == pytest.approx((3.0, 4.0, 0.9))
    assert OccupancyGrid.from_message(grid.to_message_dict()) == grid
    seven = map_from_occupancy_grid([0, 100], 2, 1, 0.1, (3.0, 4.0, 0.0, qx, qy, qz, qw))
    assert seven.origin == pytest.approx((3.0, 4.0, 0.9))
    # An unnormalised quaternion is normalised first, as tf2 does.
    assert yaw_from_quaternion(0, 0, 2 * qz, 2 * qw) == pytest.approx(0.9)


def test_cell_zero_lies_at_the_origin_in_world_coordinates():
    yaw = 0.6
    the_map = map_from_occupancy_grid([0] * 12, 4, 3, 0.5, (10.0, 20.0, yaw))
    x, y = pixel_to_world(the_map, 2, 0)  # bottom-left pixel = grid cell (0, 0)
    centre = np.array([0.25, 0.25])
    rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    assert (x, y) == pytest.approx(tuple(np.array([10.0, 20.0]) + rotation @ centre))


@pytest.mark.parametrize(
    "problem, call",
    [
        ("cells", lambda: map_from_occupancy_grid([0, 0, 0], 2, 2, 0.1)),
        ("no free cell", lambda: map_from_occupancy_grid([100, -1], 2, 1, 0.1)),
        ("tilts", lambda: map_from_occupancy_grid([0], 1, 1, 0.1, (0, 0, 0, 0.3, 0.0, 0.0, 0.95))),
        ("not a rotation", lambda: map_from_occupancy_grid([0], 1, 1, 0.1, (0, 0, 0, 0, 0, 0, 0))),
        ("resolution", lambda: map_from_occupancy_grid([0], 1, 1, 0.0)),
        ("int8", lambda: map_from_occupancy_grid([0, 300], 2, 1, 0.1)),
    ],
)
def test_bad_grids_raise_map_error(problem, call):
    with pytest.raises(MapError, match=problem):
        call()


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("yaw", YAWS)
def test_trinary_yaml_write_then_load_is_equal(tmp_path, shape, yaw):
    grid = random_grid(shape, seed=7 + shape[1], yaw=yaw)
    image = save_map_yaml(grid, tmp_path / "map.yaml")
    assert image.read_bytes()[:2] == b"P5"  # binary PGM, as map_saver writes
    loaded = load_map(tmp_path / "map.yaml")
    assert occupancy_grid_from_map(loaded) == grid


@pytest.mark.parametrize("yaw", YAWS)
def test_raw_yaml_write_then_load_is_exact_for_every_value(tmp_path, yaw):
    grid = random_grid((9, 23), seed=3, values=np.arange(-1, 101), yaw=yaw)
    save_map_yaml(grid, tmp_path / "raw.yaml", mode="raw")
    assert occupancy_grid_from_map(load_map(tmp_path / "raw.yaml")) == grid


def test_scale_yaml_follows_nav2_loader_rules(tmp_path):
    grid = random_grid((11, 19), seed=5, values=np.arange(-1, 101))
    image_path = save_map_yaml(grid, tmp_path / "scale.yaml", mode="scale")
    assert image_path.suffix == ".png"
    rgba = np.asarray(Image.open(image_path))
    assert rgba.shape[2] == 4
    loaded = load_map(tmp_path / "scale.yaml").occupancy
    expected = np.vectorize(
        lambda grey, alpha: nav2_cell(int(grey), int(alpha), mode="scale", negate=0, free=0.196, occupied=0.65)
    )(rgba[..., 0], rgba[..., 3])
    assert np.array_equal(loaded, expected)
    # Free, occupied and unknown survive a scale-mode round trip.
    cells = grid.cells()
    for value in (0, 100, -1):
        assert np.all(loaded[cells == value] == value)


def test_negate_reads_the_inverted_image_as_the_same_grid(tmp_path):
    grid = random_grid((6, 10), seed=11)
    image_path = save_map_yaml(grid, tmp_path / "map.yaml")
    grey = np.asarray(Image.open(image_path))
    Image.fromarray(255 - grey).save(tmp_path / "negated.pgm")
    text = (tmp_path / "map.yaml").read_text().replace("map.pgm", "negated.pgm").replace("negate: 0", "negate: 1")
    # 255 - 205 = 50: with negate its occ is 50 / 255 = 0.196, above free_thresh, still unknown.
    (tmp_path / "negated.yaml").write_text(text)
    assert occupancy_grid_from_map(load_map(tmp_path / "negated.yaml")) == grid


@pytest.mark.parametrize("free, occupied", [(0.1, 0.9), (0.196, 0.65), (0.05, 0.3)])
def test_trinary_thresholds_split_intermediate_cells_as_map_saver(tmp_path, free, occupied):
    values = np.arange(0, 101)
    grid = OccupancyGrid(data=values, width=101, height=1, resolution=1.0)
    save_map_yaml(grid, tmp_path / "t.yaml", free_thresh=free, occupied_thresh=occupied)
    loaded = load_map(tmp_path / "t.yaml").occupancy[0]
    expected = np.where(values <= round(free * 100), 0, np.where(values >= round(occupied * 100), 100, -1))
    assert np.array_equal(loaded, expected)


def test_nav2_default_free_thresh_would_read_unknown_as_free(tmp_path):
    # Why the writer's default is 0.196: nav2's 0.25 turns map_saver's unknown grey 205 into free.
    grid = OccupancyGrid(data=[0, -1], width=2, height=1, resolution=1.0)
    save_map_yaml(grid, tmp_path / "nav2.yaml", free_thresh=0.25)
    assert load_map(tmp_path / "nav2.yaml").occupancy.tolist() == [[0, 0]]
    save_map_yaml(grid, tmp_path / "ours.yaml")
    assert load_map(tmp_path / "ours.yaml").occupancy.tolist() == [[0, -1]]


def test_a_drawn_sketch_saves_and_loads_with_the_same_free_space(tmp_path):
    rng = np.random.default_rng(1)
    grey = np.where(rng.random((40, 60)) > 0.3, 255, 0).astype(np.uint8)
    sketch = map_from_array(grey)
    with pytest.raises(ParameterError, match="resolution"):
        save_map_yaml(sketch, tmp_path / "sketch.yaml")
    save_map_yaml(sketch, tmp_path / "sketch.yaml", resolution=0.02, origin=(-1.0, -0.5, 0.25))
    loaded = load_map(tmp_path / "sketch.yaml")
    assert np.array_equal(loaded.free, sketch.free)
    assert loaded.resolution == 0.02 and loaded.origin == (-1.0, -0.5, 0.25)


def test_a_label_map_saves_its_free_mask(tmp_path):
    labels = np.zeros((20, 30), np.int32)
    labels[2:18, 2:14], labels[2:18, 16:28] = 1, 2
    save_map_yaml(map_from_array(labels > 0), tmp_path / "labels.yaml", resolution=0.1)
    assert np.array_equal(load_map(tmp_path / "labels.yaml").free, labels > 0)


@pytest.mark.parametrize(
    "options, problem",
    [({"mode": "binary"}, "mode"), ({"free_thresh": 0.7}, "below"), ({"occupied_thresh": 1.5}, "occupied_thresh")],
)
def test_bad_save_options_raise_parameter_error(tmp_path, options, problem):
    grid = OccupancyGrid(data=[0], width=1, height=1, resolution=1.0)
    with pytest.raises(ParameterError, match=problem):
        save_map_yaml(grid, tmp_path / "x.yaml", **options)
    assert not list(Path(tmp_path).iterdir())


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("mode", ["trinary", "raw"])
def test_generated_floor_plans_survive_grid_and_yaml_round_trips(tmp_path, seed, mode):
    from scipy import ndimage

    from ursim_core.io.maps import Map
    from ursim_core.synth import generate_floor_plan, sketchify

    plan = generate_floor_plan(seed=seed)
    # A robot's view of the plan: free inside, walls occupied, what lies beyond the walls unknown.
    building = ndimage.binary_fill_holes(ndimage.binary_closing(plan.free, iterations=6))
    occupancy = np.where(plan.free, 0, np.where(building, 100, -1)).astype(np.int8)
    robot_map = Map(free=plan.free, occupancy=occupancy, resolution=0.05, origin=(-12.5, 3.0, 0.1 * seed))
    grid = occupancy_grid_from_map(robot_map)
    assert (
        occupancy_grid_from_map(map_from_occupancy_grid(grid.data, grid.width, grid.height, 0.05, grid.origin)) == grid
    )
    save_map_yaml(grid, tmp_path / "plan.yaml", mode=mode)
    loaded = load_map(tmp_path / "plan.yaml")
    assert occupancy_grid_from_map(loaded) == grid
    assert np.array_equal(loaded.free, plan.free)
    # A sketch drawn from the plan (a grid without unknown space) too.
    sketch = sketchify(plan, seed=seed)
    save_map_yaml(map_from_array(sketch.free), tmp_path / "sketch.yaml", mode=mode, resolution=0.02)
    assert np.array_equal(load_map(tmp_path / "sketch.yaml").free, sketch.free)
