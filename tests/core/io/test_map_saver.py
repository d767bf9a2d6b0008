"""The map_server writer (save_map_yaml), checked against the loader rules of nav2's map_io."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from io_helpers import SHAPES, YAWS, nav2_cell, random_grid
from PIL import Image

from ursim_core.errors import ParameterError
from ursim_core.io.map_saver import save_map_yaml
from ursim_core.io.maps import load_map, map_from_array
from ursim_core.io.occupancy_grid import OccupancyGrid, map_from_occupancy_grid, occupancy_grid_from_map


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
