"""Synthetic floor plans and sketch-like copies of them, with exact ground truth.

Used for the bundled example pair, for tests with known answers and for the scale
benchmarks. A floor plan is a building of horizontal corridors (one per "band") with
rooms above and below each, joined by doors, and a vertical corridor linking the bands.
Every free pixel carries a *place* id (room or corridor), so the ground truth of any
segmentation or match is known.

:func:`sketchify` turns a plan into what a person might draw from memory: a different
overall scale, smooth local scale distortion, wobbly walls, a room left out and an extra
corridor stub that does not exist. Place ids are carried through the warp with
nearest-neighbour sampling, so the ground truth stays exact.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import cv2
import networkx as nx
import numpy as np

from ursim_core.graph import region_graph

__all__ = [
    "FloorPlan",
    "Sketch",
    "generate_floor_plan",
    "sketchify",
    "ground_truth_pairs",
    "ground_truth_correspondences",
    "make_pair",
    "make_large_building",
    "save_example",
]


@dataclass(frozen=True, eq=False)
class FloorPlan:
    """A generated building.

    Attributes
    ----------
    free : ndarray of bool
        True for free space.
    places : ndarray of int32
        Place id of every free pixel (0 on walls and outside). Doors belong to their room.
    kinds : dict
        Place id -> 'room' or 'corridor'.
    graph : networkx.Graph
        Places joined by a door or an opening.
    """

    free: np.ndarray
    places: np.ndarray
    kinds: dict[int, str]
    graph: nx.Graph = field(repr=False)


@dataclass(frozen=True, eq=False)
class Sketch:
    """A sketch-like copy of a plan.

    Attributes
    ----------
    free, places : ndarray
        As in :class:`FloorPlan`; place ids are those of the plan, plus ``extra`` ids.
    dropped : tuple of int
        Places of the plan not drawn.
    extra : tuple of int
        Places drawn that do not exist in the plan.
    """

    free: np.ndarray
    places: np.ndarray
    dropped: tuple[int, ...] = ()
    extra: tuple[int, ...] = ()


def _split(length: int, low: int, high: int, rng: np.random.Generator) -> list[int]:
    """Cut ``length`` into pieces of ``low..high`` (the last one absorbs the rest)."""
    pieces: list[int] = []
    left = length
    while left > high:
        piece = int(rng.integers(low, high + 1))
        if left - piece < low:
            piece = left - low
        pieces.append(piece)
        left -= piece
    pieces.append(left)
    return pieces


def generate_floor_plan(
    *,
    shape: tuple[int, int] = (400, 520),
    seed: int = 0,
    corridor_width: int = 30,
    wall: int = 4,
    door_width: int = 10,
    room_depth: tuple[int, int] = (70, 110),
    room_width: tuple[int, int] = (60, 150),
    margin: int = 12,
) -> FloorPlan:
    """Generate a floor plan of rooms along corridors.

    Parameters
    ----------
    shape : (rows, cols)
        Image size.
    seed : int
        Seed of the random generator; the same seed gives the same plan.
    corridor_width, wall, door_width : int
        Sizes in pixels. Doors are narrower than rooms and corridors so a room
        segmentation can find them.
    room_depth, room_width : (low, high)
        Ranges of room sizes in pixels.

    Examples
    --------
    >>> plan = generate_floor_plan(seed=1)
    >>> plan.free.shape, plan.free.dtype
    ((400, 520), dtype('bool'))
    >>> bool((plan.places > 0).sum() == plan.free.sum())
    True
    """
    rng = np.random.default_rng(seed)
    rows, cols = shape
    places = np.zeros(shape, np.int32)
    kinds: dict[int, str] = {}
    graph = nx.Graph()
    next_id = 1

    def new_place(kind: str) -> int:
        nonlocal next_id
        kinds[next_id] = kind
        graph.add_node(next_id, kind=kind)
        next_id += 1
        return next_id - 1

    band = 2 * room_depth[1] + corridor_width + 4 * wall
    n_bands = max(1, (rows - 2 * margin) // band)
    top = margin + ((rows - 2 * margin) - n_bands * band) // 2
    spine_width = corridor_width
    left, right = margin + wall, cols - margin - wall
    spine = None
    if n_bands > 1:
        spine = new_place("corridor")
        spine_left = left
        left = spine_left + spine_width + wall
    corridors = []
    for b in range(n_bands):
        r0 = top + b * band
        depth_up = int(rng.integers(room_depth[0], room_depth[1] + 1))
        depth_down = int(rng.integers(room_depth[0], room_depth[1] + 1))
        corridor_top = r0 + wall + depth_up + wall
        corridor = new_place("corridor")
        corridors.append((corridor, corridor_top))
        places[corridor_top:corridor_top + corridor_width, left:right] = corridor
        for side, (r_start, depth) in enumerate(((corridor_top - wall - depth_up, depth_up),
                                                 (corridor_top + corridor_width + wall, depth_down))):
            c = left
            for width in _split(right - left, room_width[0] + wall, room_width[1] + wall, rng):
                room_cols = (c, c + width - wall)
                c += width
                if room_cols[1] - room_cols[0] < door_width + 2 * wall:
                    continue
                room = new_place("room")
                places[r_start:r_start + depth, room_cols[0]:room_cols[1]] = room
                door_col = int(rng.integers(room_cols[0] + wall, room_cols[1] - door_width - wall + 1))
                door_rows = (r_start + depth, corridor_top) if side == 0 else (corridor_top + corridor_width, r_start)
                places[door_rows[0]:door_rows[1], door_col:door_col + door_width] = room
                graph.add_edge(room, corridor)
    if spine is not None:
        first, last = corridors[0][1], corridors[-1][1] + corridor_width
        places[first:last, spine_left:spine_left + spine_width] = spine
        for corridor, corridor_top in corridors:
            places[corridor_top:corridor_top + corridor_width, spine_left + spine_width:left] = corridor
            graph.add_edge(spine, corridor)
    return FloorPlan(free=places > 0, places=places, kinds=kinds, graph=graph)


def _smooth_field(shape: tuple[int, int], cells: int, amplitude: float, rng: np.random.Generator) -> np.ndarray:
    coarse = rng.uniform(-amplitude, amplitude, size=(cells + 1, cells + 1)).astype(np.float32)
    return cv2.resize(coarse, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)


def _stretch(coords: np.ndarray, length: int, jitter: float, rng: np.random.Generator, *, knots: int = 6) -> np.ndarray:
    """Monotone piecewise-linear re-parametrisation of one axis (segments scaled by 1 +- jitter)."""
    factors = rng.uniform(1 - jitter, 1 + jitter, size=knots)
    drawn = np.concatenate([[0.0], np.cumsum(factors)]) / factors.sum() * length
    true = np.linspace(0.0, length, knots + 1)
    return np.interp(coords, drawn, true).astype(np.float32)


def _leaf_rooms(plan: FloorPlan) -> list[int]:
    return [p for p, kind in sorted(plan.kinds.items()) if kind == "room" and plan.graph.degree(p) == 1]


def sketchify(
    plan: FloorPlan,
    *,
    seed: int = 0,
    scale: float = 1.3,
    scale_jitter: float = 0.35,
    wobble: float = 2.0,
    rotation_deg: float = 3.0,
    pen_width: int = 1,
    drop_room: bool = True,
    extra_corridor: bool = True,
) -> Sketch:
    """Turn a plan into a sketch-like map with known place ids.

    Parameters
    ----------
    plan : FloorPlan
    seed : int
        Seed of the random generator.
    scale : float
        Overall size of the sketch relative to the plan.
    scale_jitter : float
        Local scale distortion: each of a few bands along each axis is drawn
        ``1 +- scale_jitter`` times its true size.
    wobble : float
        Amplitude in pixels of the hand-drawn wobble of the walls.
    rotation_deg : float
        Largest overall rotation.
    pen_width : int
        Walls are thickened by this many pixels on each side.
    drop_room, extra_corridor : bool
        Leave out one dead-end room; add a corridor stub that the plan does not have.

    Examples
    --------
    >>> plan = generate_floor_plan(seed=2)
    >>> sketch = sketchify(plan, seed=2)
    >>> len(sketch.dropped), len(sketch.extra)
    (1, 1)
    >>> bool(np.isin(sketch.dropped, sketch.places).any())
    False
    """
    rng = np.random.default_rng(seed)
    places = plan.places.copy()
    dropped: tuple[int, ...] = ()
    extra: tuple[int, ...] = ()
    if drop_room and _leaf_rooms(plan):
        victim = int(rng.choice(_leaf_rooms(plan)))
        places[places == victim] = 0
        dropped = (victim,)
    if extra_corridor:
        corridor = min(p for p, kind in plan.kinds.items() if kind == "corridor")
        rows_c, cols_c = np.nonzero(places == corridor)
        stub = max(plan.kinds) + 1
        width = max(8, int((rows_c.max() - rows_c.min() + 1) * 0.6))
        mid = (int(rows_c.min()) + int(rows_c.max())) // 2
        # A dead end beyond the corridor's far end, through the outer wall.
        end = int(cols_c.max()) + 1
        length = min(places.shape[1] - end - 2, 60)
        if length > 10:
            places[mid - width // 2: mid + width // 2, end:end + length] = stub
            extra = (stub,)
    rows, cols = places.shape
    out_rows, out_cols = int(round(rows * scale)), int(round(cols * scale))
    angle = np.deg2rad(rng.uniform(-rotation_deg, rotation_deg))
    grid_r, grid_c = np.mgrid[0:out_rows, 0:out_cols].astype(np.float32)
    # Inverse map: sketch pixel -> plan pixel, about the centres.
    centre_out = np.array([out_rows / 2, out_cols / 2], np.float32)
    centre_in = np.array([rows / 2, cols / 2], np.float32)
    dr, dc = (grid_r - centre_out[0]) / scale, (grid_c - centre_out[1]) / scale
    cos, sin = np.cos(angle), np.sin(angle)
    src_r = cos * dr - sin * dc + centre_in[0]
    src_c = sin * dr + cos * dc + centre_in[1]
    # Local scale: people draw some rooms too big and others too small, with straight walls, so
    # each axis is stretched by a monotone piecewise-linear map rather than bent.
    src_r = _stretch(src_r, rows, scale_jitter, rng)
    src_c = _stretch(src_c, cols, scale_jitter, rng)
    # Hand-drawn wobble: a weak field varying every few tens of pixels.
    cells = max(4, int(max(out_rows, out_cols) / 40))
    src_r += _smooth_field((out_rows, out_cols), cells, wobble, rng)
    src_c += _smooth_field((out_rows, out_cols), cells, wobble, rng)
    warped = cv2.remap(places, src_c.astype(np.float32), src_r.astype(np.float32), cv2.INTER_NEAREST,
                       borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    # A pen draws thicker walls than a laser sees.
    pen = cv2.erode((warped > 0).astype(np.uint8), np.ones((3, 3), np.uint8), iterations=pen_width)
    warped = np.where(pen > 0, warped, 0).astype(np.int32)
    return Sketch(free=warped > 0, places=warped, dropped=dropped, extra=extra)


def _interior_points(places: np.ndarray) -> dict[int, tuple[int, int]]:
    return {int(p): tuple(int(v) for v in point) for p, point in region_graph(places).nodes(data="interior")}


def ground_truth_pairs(plan: FloorPlan, sketch: Sketch) -> list[tuple[int, tuple[int, int], tuple[int, int]]]:
    """One (place, sketch point, plan point) per place present in both maps.

    The points are each place's most interior pixel (farthest from its border).

    Examples
    --------
    >>> plan = generate_floor_plan(seed=3); sketch = sketchify(plan, seed=3)
    >>> pairs = ground_truth_pairs(plan, sketch)
    >>> all(sketch.places[s] == p and plan.places[m] == p for p, s, m in pairs)
    True
    """
    in_sketch, in_plan = _interior_points(sketch.places), _interior_points(plan.places)
    return [(p, in_sketch[p], in_plan[p]) for p in sorted(in_plan) if p in in_sketch]


def ground_truth_correspondences(plan: FloorPlan, sketch: Sketch, *, sketch_path: Path | None = None,
                                 metric_path: Path | None = None):
    """The ground truth as a :class:`~ursim_core.correspondences.Correspondences` value."""
    from ursim_core.correspondences import Clique, Correspondences, MapRef

    cliques = tuple(
        Clique(id=index, sketch_points=(s,), metric_points=(m,), source="manual",
               note=f"place {place} ({plan.kinds.get(place, 'extra')})")
        for index, (place, s, m) in enumerate(ground_truth_pairs(plan, sketch), start=1)
    )
    return Correspondences(
        sketch=MapRef(path=sketch_path, size=tuple(sketch.free.shape)),
        metric=MapRef(path=metric_path, size=tuple(plan.free.shape)),
        cliques=cliques,
        annotator="ursim_core.synth (generated ground truth)",
    )


def make_pair(*, seed: int = 0, shape: tuple[int, int] = (400, 520), **sketch_options) -> tuple[FloorPlan, Sketch]:
    """A plan and its sketch from one seed.

    Examples
    --------
    >>> plan, sketch = make_pair(seed=4)
    >>> sketch.free.shape[0] > plan.free.shape[0]
    True
    """
    plan = generate_floor_plan(shape=shape, seed=seed)
    return plan, sketchify(plan, seed=seed, **sketch_options)


def make_large_building(size: int = 4000, *, seed: int = 0) -> FloorPlan:
    """A square building of ``size`` px with many bands of rooms (hundreds at 4000 px).

    Examples
    --------
    >>> plan = make_large_building(800)
    >>> sum(kind == "room" for kind in plan.kinds.values()) > 20
    True
    """
    return generate_floor_plan(shape=(size, size), seed=seed)


def save_example(plan: FloorPlan, sketch: Sketch, folder: str | Path) -> None:
    """Write ``metric.png``, ``sketch.png`` (255 free, 0 wall) and ``ground_truth.json``."""
    from ursim_core.correspondences import MapRef, save_correspondences
    from ursim_core.maps import load_map
    from ursim_core.render import save_png

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = {"metric": folder / "metric.png", "sketch": folder / "sketch.png"}
    save_png(paths["metric"], np.where(plan.free, 255, 0).astype(np.uint8))
    save_png(paths["sketch"], np.where(sketch.free, 255, 0).astype(np.uint8))
    corr = ground_truth_correspondences(plan, sketch, sketch_path=paths["sketch"], metric_path=paths["metric"])
    refs = {}
    for side, path in paths.items():
        loaded = load_map(path)
        refs[side] = MapRef(path=path.resolve(), sha256=loaded.sha256, size=tuple(loaded.shape))
    import dataclasses

    save_correspondences(dataclasses.replace(corr, sketch=refs["sketch"], metric=refs["metric"]),
                         folder / "ground_truth.json")
