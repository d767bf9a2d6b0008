"""Synthetic floor plans and sketch-like copies of them, with exact ground truth.

Used for the bundled example pair, for tests with known answers and for the scale
benchmarks. A floor plan is an office building made of horizontal corridors (one per
"band" of the building) lined with rooms on both sides, and vertical corridors at one or
both ends (and, in wide buildings, in between) that cross them. Every free pixel carries
the id of the *place* it belongs to: each room, each corridor segment between two
crossings, each crossing and each dead-end corridor is a place. Door pixels (the gap in
the wall) belong to the room, so every free pixel has exactly one place.

:func:`sketchify` turns a plan into what a person might draw from memory (see
``/work/shared/design/paper.md``): a different overall scale, rooms drawn out of
proportion, slightly bent and wobbly thick walls, a small overall rotation, a dead-end
corridor left out and a corridor stub added that the building does not have. Place ids
are carried through the warp with nearest-neighbour sampling, so the ground truth stays
exact.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import networkx as nx
import numpy as np
from scipy import ndimage

from ursim_core.errors import ParameterError

__all__ = [
    "Place",
    "FloorPlan",
    "Sketch",
    "generate_floor_plan",
    "sketchify",
    "interior_points",
    "ground_truth_pairs",
    "ground_truth_correspondences",
    "make_pair",
    "make_large_building",
    "save_example",
]


@dataclass(frozen=True)
class Place:
    """One place of a floor plan.

    Attributes
    ----------
    id : int
        Its label in :attr:`FloorPlan.rooms` (1..N).
    kind : {'room', 'corridor'}
    role : {'room', 'segment', 'crossing', 'dead end'}
        What kind of corridor piece it is: a stretch between crossings, the square where
        two corridors cross, or a corridor that leads nowhere else.
    interior : (int, int)
        A (row, col) point well inside the place (see :func:`interior_points`).
    """

    id: int
    kind: str
    role: str
    interior: tuple[int, int]


@dataclass(frozen=True, eq=False)
class FloorPlan:
    """A generated building.

    Attributes
    ----------
    free : ndarray of bool
        True for free space.
    rooms : ndarray of int32
        Place id of every free pixel, 0 on walls and outside. Doors belong to their room.
    places : list of Place
        One entry per place id, in id order.
    graph : networkx.Graph
        Node per place id (attributes ``kind``, ``role``, ``interior``); an edge joins two
        places that touch through a door (``via='door'``) or an open corridor junction
        (``via='opening'``).
    params : dict
        The sizes the plan was drawn with (``corridor_width``, ``wall_thickness``,
        ``door_width``, ``seed``).
    """

    free: np.ndarray
    rooms: np.ndarray
    places: list[Place]
    graph: nx.Graph = field(repr=False)
    params: dict = field(default_factory=dict)

    @property
    def kinds(self) -> dict[int, str]:
        """Place id -> ``'room'`` or ``'corridor'``."""
        return {place.id: place.kind for place in self.places}


@dataclass(frozen=True, eq=False)
class Sketch:
    """A sketch-like copy of a plan.

    Attributes
    ----------
    free : ndarray of bool
        True for free space.
    rooms : ndarray of int32
        Place id of every free pixel: the plan's ids, plus the ``extra`` ids.
    dropped : tuple of int
        Places of the plan that are not drawn.
    extra : tuple of int
        Places drawn that do not exist in the plan.
    notes : tuple of str
        What was changed, in words (drops, additions, scale, rotation).
    """

    free: np.ndarray
    rooms: np.ndarray
    dropped: tuple[int, ...] = ()
    extra: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()


# --------------------------------------------------------------------------- plan generation


def _split(length: int, low: int, high: int, rng: np.random.Generator) -> list[int]:
    """Cut ``length`` into pieces of ``low..high`` (the last one absorbs what is left)."""
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


def _split_in(length: int, count: int, low: int, rng: np.random.Generator) -> list[int]:
    """Cut ``length`` into exactly ``count`` pieces of at least ``low``, random proportions."""
    spare = length - count * low
    shares = np.floor(rng.dirichlet(np.full(count, 3.0)) * spare).astype(int)
    shares[: spare - shares.sum()] += 1
    return (low + shares).tolist()


def _allocate(total: int, lengths: np.ndarray) -> np.ndarray:
    """Share ``total`` items between bins in proportion to ``lengths`` (largest remainder)."""
    exact = total * lengths / lengths.sum()
    counts = np.floor(exact).astype(int)
    order = np.argsort(-(exact - counts), kind="stable")
    counts[order[: total - counts.sum()]] += 1
    return counts


def _check_sizes(shape, n_rooms, corridor_width, wall_thickness, door_width, room_depth, room_width, margin) -> None:
    if len(shape) != 2 or min(shape) < 1:
        raise ParameterError(f"shape must be (rows, cols) with positive sizes, got {shape!r}", field="shape")
    for name, value in (
        ("corridor_width", corridor_width),
        ("wall_thickness", wall_thickness),
        ("door_width", door_width),
    ):
        if int(value) != value or value < 1:
            raise ParameterError(f"must be a positive whole number of pixels, got {value!r}", field=name)
    if margin < 0:
        raise ParameterError(f"must not be negative, got {margin!r}", field="margin")
    if door_width >= corridor_width:
        raise ParameterError(
            f"doors ({door_width} px) must be narrower than corridors ({corridor_width} px) "
            "so that a room segmentation can tell them apart",
            field="door_width",
        )
    smallest_room = door_width + 2 * wall_thickness + 2
    for name, (low, high) in (("room_depth", room_depth), ("room_width", room_width)):
        if not smallest_room <= low <= high:
            raise ParameterError(
                f"must be (low, high) with {smallest_room} <= low <= high (a door and its jambs "
                f"must fit), got {(low, high)!r}",
                field=name,
            )
    if n_rooms is not None and (int(n_rooms) != n_rooms or n_rooms < 0):
        raise ParameterError(f"must be a non-negative whole number or None, got {n_rooms!r}", field="n_rooms")


def generate_floor_plan(
    *,
    shape: tuple[int, int] = (400, 512),
    n_rooms: int | None = None,
    seed: int = 0,
    corridor_width: int = 30,
    wall_thickness: int = 4,
    door_width: int = 10,
    room_depth: tuple[int, int] = (80, 140),
    room_width: tuple[int, int] = (60, 150),
    margin: int = 12,
    room_door_probability: float = 0.2,
) -> FloorPlan:
    """Generate an office floor: corridors lined with rooms, joined by doors.

    The building is cut into horizontal bands as tall as a room row, a corridor and a
    room row. Each band's corridor is crossed by vertical corridors at one or both ends
    of the building and, in buildings wider than about 1000 px, in between (two or more
    bands and two vertical corridors make loops). Every room has a door to the corridor
    in front of it; some neighbouring rooms also share a door. Rooms on the outside of
    the building are of varied depth, so the outline is not a plain rectangle.

    Parameters
    ----------
    shape : (rows, cols), keyword-only
        Image size. Everything outside the building is 0 (not free).
    n_rooms : int, optional, keyword-only
        Exact number of rooms; by default as many as the ``room_width`` range gives.
    seed : int, keyword-only
        Seed of :func:`numpy.random.default_rng`; the same seed gives the same plan.
    corridor_width, wall_thickness, door_width : int, keyword-only
        Sizes in pixels. Doors must be narrower than corridors (and much narrower than
        rooms) so that a room segmentation such as MAORIS cuts the free space at them.
    room_depth, room_width : (low, high), keyword-only
        Ranges of room sizes in pixels (depth away from the corridor, width along it).
    margin : int, keyword-only
        Outside space around the building's outer wall.
    room_door_probability : float, keyword-only
        Chance that two neighbouring rooms share a door.

    Returns
    -------
    FloorPlan

    Raises
    ------
    ParameterError
        A size is not positive, doors are not narrower than corridors, no band fits in
        ``shape`` or ``n_rooms`` rooms do not fit.

    Examples
    --------
    >>> plan = generate_floor_plan(seed=1)
    >>> plan.free.shape, plan.free.dtype, plan.rooms.dtype
    ((400, 512), dtype('bool'), dtype('int32'))
    >>> bool(np.array_equal(plan.rooms > 0, plan.free))
    True
    >>> import networkx as nx
    >>> nx.is_connected(plan.graph)
    True
    >>> sum(place.kind == "room" for place in generate_floor_plan(seed=1, n_rooms=6).places)
    6
    """
    _check_sizes(shape, n_rooms, corridor_width, wall_thickness, door_width, room_depth, room_width, margin)
    rng = np.random.default_rng(seed)
    rows, cols = (int(v) for v in shape)
    wall, cw = int(wall_thickness), int(corridor_width)
    top, bottom = margin + wall, rows - margin - wall
    left, right = margin + wall, cols - margin - wall
    smallest_room = door_width + 2 * wall + 2

    # Bands, top to bottom: (first row, corridor's first row, end row).
    bands: list[tuple[int, int, int]] = []
    end = top - wall
    while True:
        depth_up, depth_down = (int(v) for v in rng.integers(room_depth[0], room_depth[1] + 1, size=2))
        start = end + wall
        band_end = start + depth_up + wall + cw + wall + depth_down
        if band_end > bottom:
            break
        bands.append((start, start + depth_up + wall, band_end))
        end = band_end
    if not bands:
        # Not even one band of the requested depths fits: use shallower rooms.
        depth = (bottom - top - 2 * wall - cw) // 2
        if depth < smallest_room:
            raise ParameterError(f"no corridor with rooms on both sides fits in {rows} rows", field="shape")
        bands = [(top, top + depth + wall, top + 2 * depth + 2 * wall + cw)]
        end = bands[0][2]
    shift = (bottom - end) // 2
    bands = [(a + shift, b + shift, c + shift) for a, b, c in bands]

    # Vertical corridors (column intervals). At least one, so every plan has dead ends and
    # multi-band buildings are connected.
    if right - left < 2 * cw + smallest_room:
        raise ParameterError(f"the building is too narrow for a corridor and rooms ({cols} columns)", field="shape")
    ends = [("left",), ("right",), ("left", "right")][int(rng.choice(3, p=[0.4, 0.4, 0.2]))]
    verticals = []
    if "left" in ends:
        verticals.append((left, left + cw))
    if "right" in ends:
        verticals.append((right - cw, right))
    n_middle = max(0, int((right - left) / rng.uniform(600, 900)) - 1)
    spacing = (right - left) / (n_middle + 1)
    for index in range(1, n_middle + 1):
        centre = left + index * spacing + rng.uniform(-spacing / 6, spacing / 6)
        verticals.append((int(centre) - cw // 2, int(centre) - cw // 2 + cw))
    verticals.sort()
    # Column gaps between vertical corridors: each holds one corridor segment per band and
    # a run of rooms on either side of it (inset by a wall where it meets a vertical corridor).
    bounds = [left] + [c for v in verticals for c in v] + [right]
    gaps = [(a, b) for a, b in zip(bounds[::2], bounds[1::2]) if b > a]
    runs = [(a + (wall if a > left else 0), b - (wall if b < right else 0)) for a, b in gaps]

    labels = np.zeros((rows, cols), np.int32)
    graph = nx.Graph()
    meta: dict[int, tuple[str, str, tuple[int, int]]] = {}

    def add(kind: str, role: str, r0: int, r1: int, c0: int, c1: int) -> int:
        place = len(meta) + 1
        labels[r0:r1, c0:c1] = place
        meta[place] = (kind, role, ((r0 + r1 - 1) // 2, (c0 + c1 - 1) // 2))
        graph.add_node(place, kind=kind, role=role)
        return place

    # Corridors first, so corridor ids are small and stable.
    segments: dict[tuple[int, int], int] = {}
    crossings: dict[tuple[int, int], int] = {}
    for b, (_, ct, _) in enumerate(bands):
        for g, (c0, c1) in enumerate(gaps):
            segments[b, g] = add("corridor", "segment", ct, ct + cw, c0, c1)
        for v, (c0, c1) in enumerate(verticals):
            crossings[b, v] = add("corridor", "crossing", ct, ct + cw, c0, c1)
    for b in range(len(bands)):
        for g, (c0, c1) in enumerate(gaps):
            for v, (v0, v1) in enumerate(verticals):
                if v1 == c0 or v0 == c1:
                    graph.add_edge(segments[b, g], crossings[b, v], via="opening")
    for v, (c0, c1) in enumerate(verticals):
        pieces = [(bands[0][0], bands[0][1], "dead end", [0])]
        pieces += [(bands[b][1] + cw, bands[b + 1][1], "segment", [b, b + 1]) for b in range(len(bands) - 1)]
        pieces += [(bands[-1][1] + cw, bands[-1][2], "dead end", [len(bands) - 1])]
        for r0, r1, role, touching in pieces:
            place = add("corridor", role, r0, r1, c0, c1)
            for b in touching:
                graph.add_edge(place, crossings[b, v], via="opening")

    # Room rows: (band, side, run) with the rows every room of the row spans.
    room_rows = []
    for b, (start, ct, band_end) in enumerate(bands):
        room_rows.append((b, "up", start, ct - wall))
        room_rows.append((b, "down", ct + cw + wall, band_end))
    slots = [(b, side, r0, r1, g, c0, c1) for b, side, r0, r1 in room_rows for g, (c0, c1) in enumerate(runs)]
    if n_rooms is not None:
        lengths = np.array([c1 - c0 + wall for *_, c0, c1 in slots], float)
        counts = _allocate(int(n_rooms), lengths)
        if np.any(counts * (smallest_room + wall) > lengths):
            fit = int(np.sum(lengths // (smallest_room + wall)))
            raise ParameterError(
                f"{n_rooms} rooms do not fit in a {rows} x {cols} building (at most about {fit})", field="n_rooms"
            )
    for index, (b, side, r0, r1, g, c0, c1) in enumerate(slots):
        # Each piece is a room and the wall after it; the last wall falls on the run's end.
        if n_rooms is None:
            pieces = _split(c1 - c0 + wall, room_width[0] + wall, room_width[1] + wall, rng)
        elif counts[index]:
            pieces = _split_in(c1 - c0 + wall, int(counts[index]), smallest_room + wall, rng)
        else:
            continue
        outer = (b == 0 and side == "up") or (b == len(bands) - 1 and side == "down")
        corridor = segments[b, g]
        previous = None
        c = c0
        for piece in pieces:
            rc0, rc1 = c, c + piece - wall
            c += piece
            if rc1 - rc0 < smallest_room:
                previous = None
                continue
            rr0, rr1 = r0, r1
            if outer and rng.random() < 0.35:
                # Outer rooms of varied depth give the building a less regular outline.
                cut = int(rng.integers(0, (r1 - r0) * 3 // 10 + 1))
                rr0, rr1 = (r0 + cut, r1) if side == "up" else (r0, r1 - cut)
            room = add("room", "room", rr0, rr1, rc0, rc1)
            door = int(rng.integers(rc0 + wall, rc1 - door_width - wall + 1))
            door_rows = (rr1, rr1 + wall) if side == "up" else (rr0 - wall, rr0)
            labels[door_rows[0] : door_rows[1], door : door + door_width] = room
            graph.add_edge(room, corridor, via="door")
            if previous is not None and rng.random() < room_door_probability:
                other, (or0, or1) = previous
                low, high = max(rr0, or0) + wall, min(rr1, or1) - door_width - wall
                if high >= low:
                    door = int(rng.integers(low, high + 1))
                    labels[door : door + door_width, rc0 - wall : rc0] = other
                    graph.add_edge(other, room, via="door")
            previous = (room, (rr0, rr1))

    places = [Place(id=p, kind=kind, role=role, interior=point) for p, (kind, role, point) in sorted(meta.items())]
    for place in places:
        graph.nodes[place.id]["interior"] = place.interior
    params = {"corridor_width": cw, "wall_thickness": wall, "door_width": int(door_width), "seed": seed}
    return FloorPlan(free=labels > 0, rooms=labels, places=places, graph=graph, params=params)


def make_large_building(size: int = 4000, seed: int = 0) -> FloorPlan:
    """A square building of ``size`` px: many bands of rooms (about 1000 at 4000 px).

    For the scale benchmarks; default sizes (corridors 30 px, rooms 60-150 px).

    Examples
    --------
    >>> plan = make_large_building(800)
    >>> sum(place.kind == "room" for place in plan.places) > 20
    True
    """
    return generate_floor_plan(shape=(size, size), seed=seed)


# --------------------------------------------------------------------------- interior points


def interior_points(labels: np.ndarray) -> dict[int, tuple[int, int]]:
    """A point well inside every labelled region.

    The point is at (nearly, within half a pixel) the largest distance to the region's
    border, where any other label counts as border; among such points the one nearest
    the region's centroid, so a long room gets a point in its middle rather than at one
    end of its ridge.

    Parameters
    ----------
    labels : (rows, cols) integer array
        0 = no region.

    Returns
    -------
    dict
        Label -> (row, col), for every label present.

    Examples
    --------
    >>> labels = np.zeros((7, 12), np.int32)
    >>> labels[1:6, 1:6] = 1
    >>> labels[1:6, 6:11] = 2
    >>> interior_points(labels)
    {1: (3, 3), 2: (3, 8)}
    """
    labels = np.asarray(labels)
    padded = np.pad(labels, 1)
    centre = padded[1:-1, 1:-1]
    inside = (
        (centre != 0)
        & (centre == padded[:-2, 1:-1])
        & (centre == padded[2:, 1:-1])
        & (centre == padded[1:-1, :-2])
        & (centre == padded[1:-1, 2:])
    )
    distance = cv2.distanceTransform(inside.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    rows, cols = np.nonzero(labels)
    ids = labels[rows, cols].astype(np.int64)
    values = distance[rows, cols]
    top = int(ids.max(initial=0)) + 1
    best = np.full(top, -1.0, np.float32)
    np.maximum.at(best, ids, values)
    near_best = values >= best[ids] - 0.5
    counts = np.bincount(ids, minlength=top)
    safe = np.maximum(counts, 1)
    centroid_r = np.bincount(ids, weights=rows, minlength=top) / safe
    centroid_c = np.bincount(ids, weights=cols, minlength=top) / safe
    rows, cols, ids = rows[near_best], cols[near_best], ids[near_best]
    off_centre = (rows - centroid_r[ids]) ** 2 + (cols - centroid_c[ids]) ** 2
    order = np.lexsort((off_centre, ids))
    first = order[np.r_[True, ids[order][1:] != ids[order][:-1]]]
    return {int(i): (int(r), int(c)) for i, r, c in zip(ids[first], rows[first], cols[first])}


# --------------------------------------------------------------------------- sketchify


def _smooth_field(shape: tuple[int, int], cell: float, amplitude: float, rng: np.random.Generator) -> np.ndarray:
    """Random field of about ``amplitude`` that varies over ``cell`` pixels (bicubic upsampling)."""
    coarse_shape = (max(2, int(np.ceil(shape[0] / cell)) + 1), max(2, int(np.ceil(shape[1] / cell)) + 1))
    coarse = rng.uniform(-amplitude, amplitude, size=coarse_shape).astype(np.float32)
    return cv2.resize(coarse, (shape[1], shape[0]), interpolation=cv2.INTER_CUBIC)


def _stretch(coords: np.ndarray, length: int, jitter: float, rng: np.random.Generator, *, knots: int = 6) -> np.ndarray:
    """Monotone piecewise-linear map of one axis: ``knots`` bands drawn ``1 +- jitter`` times their size.

    ``coords`` are positions in the drawn (stretched) axis; the result is where they lie in the plan.
    """
    factors = rng.uniform(1 - jitter, 1 + jitter, size=knots)
    drawn = np.concatenate([[0.0], np.cumsum(factors)]) / factors.sum() * length
    true = np.linspace(0.0, length, knots + 1)
    return np.interp(coords, drawn, true).astype(np.float32)


_DIRECTIONS = {"up": (-1, 0), "down": (1, 0), "left": (0, -1), "right": (0, 1)}


def _stub_candidates(labels: np.ndarray, plan: FloorPlan, width: int, length: int) -> list[tuple[int, str, tuple]]:
    """Rectangles (r0, r1, c0, c1) that continue a corridor through the outer wall into open space.

    ``labels`` is the padded label image of the plan (before anything is dropped, so a stub
    never redraws a dropped corridor). The part beyond the wall, grown by a wall's
    thickness, must touch nothing.
    """
    wall = plan.params.get("wall_thickness", 4)
    boxes = ndimage.find_objects(labels)
    found = []
    for place in plan.places:
        if place.kind != "corridor" or boxes[place.id - 1] is None:
            continue
        rows, cols = boxes[place.id - 1]
        r_mid, c_mid = (rows.start + rows.stop) // 2, (cols.start + cols.stop) // 2
        for name, (dr, dc) in _DIRECTIONS.items():
            if dr:
                c0 = c_mid - width // 2
                r0 = rows.start - length if dr < 0 else rows.stop
                rect = (r0, r0 + length, c0, c0 + width)
                through = (rows.start - wall, rows.start) if dr < 0 else (rows.stop, rows.stop + wall)
                beyond = (r0 - wall, rows.start - wall) if dr < 0 else (rows.stop + wall, r0 + length + wall)
                checks = [(through, (c0, c0 + width)), (beyond, (c0 - wall, c0 + width + wall))]
            else:
                r0 = r_mid - width // 2
                c0 = cols.start - length if dc < 0 else cols.stop
                rect = (r0, r0 + width, c0, c0 + length)
                through = (cols.start - wall, cols.start) if dc < 0 else (cols.stop, cols.stop + wall)
                beyond = (c0 - wall, cols.start - wall) if dc < 0 else (cols.stop + wall, c0 + length + wall)
                checks = [((r0, r0 + width), through), ((r0 - wall, r0 + width + wall), beyond)]
            inside_image = all(
                0 <= a < b <= n
                for (a, b), n in [(span, labels.shape[axis]) for check in checks for axis, span in enumerate(check)]
            )
            if inside_image and not any(labels[r[0] : r[1], c[0] : c[1]].any() for r, c in checks):
                found.append((place.id, name, rect))
    return found


def sketchify(
    plan: FloorPlan,
    *,
    seed: int = 0,
    scale: float = 1.3,
    scale_jitter: float = 0.3,
    wobble: float = 2.0,
    rotation_deg: float = 3.0,
    pen_width: float = 1.5,
    pen_noise: float = 1.0,
    drop_corridor: bool = True,
    drop_room: bool = False,
    extra_corridor: bool = True,
) -> Sketch:
    """Turn a plan into a sketch-like map whose place ids are known.

    Parameters
    ----------
    plan : FloorPlan
    seed : int, keyword-only
        Seed of the random generator; the same plan and seed give the same sketch.
    scale : float, keyword-only
        Overall size of the sketch relative to the plan.
    scale_jitter : float, keyword-only
        Local scale distortion: each of six bands along each axis is drawn ``1 +- scale_jitter``
        times its true size (walls stay straight; some rooms come out too big, others too
        small). Keep it below about 0.4 so that doors stay open.
    wobble : float, keyword-only
        Amplitude in pixels of a smooth displacement field varying over about 40 px: walls bend.
    rotation_deg : float, keyword-only
        Largest overall rotation, in degrees.
    pen_width, pen_noise : float, keyword-only
        Walls are redrawn as strokes thicker than the plan's by ``pen_width +- pen_noise``
        pixels on each side, the variation being smooth along the wall (a hand-drawn stroke).
        ``pen_noise`` must not exceed ``pen_width``.
    drop_corridor : bool, keyword-only
        Leave out one dead-end corridor (when the plan has one).
    drop_room : bool, keyword-only
        Leave out one room that has a single door.
    extra_corridor : bool, keyword-only
        Add a corridor stub, narrower than the corridors, through the outer wall off a corridor
        that is not a dead end (when one reaches the outer wall; every generated plan has
        one). The plan does not have it; its id is the plan's largest id + 1.

    Returns
    -------
    Sketch
        Cropped around the drawing with a margin; its size is not the plan's.

    Raises
    ------
    ParameterError
        A size or amplitude is negative, ``scale`` is not positive, ``scale_jitter`` is not
        below 1 or ``pen_noise`` exceeds ``pen_width``.

    Examples
    --------
    >>> plan = generate_floor_plan(seed=2)
    >>> sketch = sketchify(plan, seed=2)
    >>> len(sketch.dropped), len(sketch.extra)
    (1, 1)
    >>> bool(np.isin(sketch.dropped, sketch.rooms).any()), bool(np.isin(sketch.extra, plan.rooms).any())
    (False, False)
    """
    for name, value in (
        ("wobble", wobble),
        ("rotation_deg", rotation_deg),
        ("pen_width", pen_width),
        ("pen_noise", pen_noise),
        ("scale_jitter", scale_jitter),
    ):
        if not value >= 0:
            raise ParameterError(f"must not be negative, got {value!r}", field=name)
    if not scale > 0:
        raise ParameterError(f"must be positive, got {scale!r}", field="scale")
    if not scale_jitter < 1:
        raise ParameterError(f"must be below 1 (a band cannot vanish), got {scale_jitter!r}", field="scale_jitter")
    if pen_noise > pen_width:
        raise ParameterError(
            f"must not exceed pen_width ({pen_width}) or walls would get thinner than in the plan, got {pen_noise!r}",
            field="pen_noise",
        )
    rng = np.random.default_rng(seed)
    cw = int(plan.params.get("corridor_width", 30))
    # Room around the building for the stub, the rotation and the wobble.
    pad = 3 * cw + 10
    original = np.pad(plan.rooms, pad)
    labels = original.copy()
    notes: list[str] = []
    dropped: list[int] = []
    kinds = plan.kinds

    def drop(candidates: list[int], what: str) -> None:
        if candidates:
            victim = int(rng.choice(candidates))
            labels[labels == victim] = 0
            dropped.append(victim)
            notes.append(f"place {victim} ({what}) is not drawn")

    if drop_corridor:
        drop([p.id for p in plan.places if p.kind == "corridor" and plan.graph.degree(p.id) == 1], "dead-end corridor")
    if drop_room:
        drop([p.id for p in plan.places if p.kind == "room" and plan.graph.degree(p.id) == 1], "room")
    extra: list[int] = []
    if extra_corridor:
        width = int(round(cw * rng.uniform(0.6, 0.85)))
        length = int(round(cw * rng.uniform(1.6, 2.6)))
        # Not off a dead end: a dead end drawn longer is no new place to the eye.
        candidates = [
            c
            for c in _stub_candidates(original, plan, width, length)
            if c[0] not in dropped and plan.graph.degree(c[0]) > 1
        ]
        if candidates:
            parent, direction, (r0, r1, c0, c1) = candidates[int(rng.integers(len(candidates)))]
            stub = max(kinds, default=0) + 1
            labels[r0:r1, c0:c1] = stub
            extra.append(stub)
            notes.append(f"place {stub} (corridor stub, {width} x {length} px) added {direction} of place {parent}")

    rows, cols = labels.shape
    out_shape = (int(round(rows * scale)), int(round(cols * scale)))
    angle = float(rng.uniform(-rotation_deg, rotation_deg))
    notes.append(f"drawn at scale {scale:g} (local +-{scale_jitter:g}), rotated {angle:+.1f} degrees")
    # Inverse map, sketch pixel -> plan pixel: undo the rotation and scale about the centres,
    # then the per-axis stretch, then add the wobble.
    grid_r, grid_c = np.mgrid[0 : out_shape[0], 0 : out_shape[1]].astype(np.float32)
    dr = (grid_r - out_shape[0] / 2) / scale
    dc = (grid_c - out_shape[1] / 2) / scale
    del grid_r, grid_c
    cos, sin = np.float32(np.cos(np.deg2rad(angle))), np.float32(np.sin(np.deg2rad(angle)))
    src_r = _stretch(cos * dr - sin * dc + rows / 2, rows, scale_jitter, rng)
    src_c = _stretch(sin * dr + cos * dc + cols / 2, cols, scale_jitter, rng)
    del dr, dc
    src_r += _smooth_field(out_shape, 40, wobble, rng)
    src_c += _smooth_field(out_shape, 40, wobble, rng)
    warped = cv2.remap(labels, src_c, src_r, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    del src_r, src_c
    # Hand-drawn walls: strokes thicker than the plan's walls, their edge varying smoothly.
    distance = cv2.distanceTransform((warped > 0).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    stroke = pen_width + _smooth_field(out_shape, 25, pen_noise, rng)
    free = distance > stroke
    # A stroke can cut off a sliver of a corner; such crumbs are not part of any drawing.
    count, components, stats, _ = cv2.connectedComponentsWithStats(free.astype(np.uint8), connectivity=4)
    crumbs = stats[:, cv2.CC_STAT_AREA] < max(4, plan.params.get("door_width", 10) ** 2 // 4)
    crumbs[0] = True
    free = ~crumbs[components]
    warped = np.where(free, warped, 0).astype(np.int32)
    used_rows, used_cols = np.nonzero(free.any(axis=1))[0], np.nonzero(free.any(axis=0))[0]
    if used_rows.size:
        border = int(round(20 * scale))
        r0, c0 = max(0, used_rows[0] - border), max(0, used_cols[0] - border)
        r1, c1 = used_rows[-1] + 1 + border, used_cols[-1] + 1 + border
        warped, free = warped[r0:r1, c0:c1].copy(), free[r0:r1, c0:c1].copy()
    return Sketch(free=free, rooms=warped, dropped=tuple(dropped), extra=tuple(extra), notes=tuple(notes))


# --------------------------------------------------------------------------- ground truth


def _shared_points(plan: FloorPlan, sketch: Sketch) -> list[tuple[int, tuple[int, int], tuple[int, int]]]:
    in_sketch, in_plan = interior_points(sketch.rooms), interior_points(plan.rooms)
    return [(place, in_sketch[place], in_plan[place]) for place in sorted(in_plan) if place in in_sketch]


def ground_truth_pairs(plan: FloorPlan, sketch: Sketch) -> list[tuple[list[tuple[int, int]], list[tuple[int, int]]]]:
    """One (sketch points, metric points) clique per place drawn in both maps, by place id.

    Each side has one point, the place's most interior pixel (see :func:`interior_points`).

    Examples
    --------
    >>> plan = generate_floor_plan(seed=3)
    >>> sketch = sketchify(plan, seed=3)
    >>> pairs = ground_truth_pairs(plan, sketch)
    >>> len(pairs) == len(plan.places) - len(sketch.dropped)
    True
    >>> all(sketch.rooms[s[0]] == plan.rooms[m[0]] for s, m in pairs)
    True
    """
    return [([s], [m]) for _, s, m in _shared_points(plan, sketch)]


def ground_truth_correspondences(
    plan: FloorPlan, sketch: Sketch, *, sketch_path: str | Path | None = None, metric_path: str | Path | None = None
):
    """The ground truth as a :class:`~ursim_core.correspondences.codec.Correspondences` value.

    One clique per place in both maps, numbered from 1 in place order, noted
    ``"place <id> <kind>"``; region lists are left empty (they depend on a segmentation,
    see :func:`ursim_core.correspondences.codec.assign_regions`).

    Examples
    --------
    >>> plan, sketch = make_pair(seed=5)
    >>> corr = ground_truth_correspondences(plan, sketch)
    >>> corr.cliques[0].note
    'place 1 corridor'
    >>> corr.metric.size == plan.free.shape
    True
    """
    from ursim_core.correspondences.codec import Clique, Correspondences, MapRef

    kinds = plan.kinds
    cliques = tuple(
        Clique(id=index, sketch_points=(s,), metric_points=(m,), source="manual", note=f"place {place} {kinds[place]}")
        for index, (place, s, m) in enumerate(_shared_points(plan, sketch), start=1)
    )
    return Correspondences(
        sketch=MapRef(path=sketch_path, size=tuple(sketch.free.shape)),
        metric=MapRef(path=metric_path, size=tuple(plan.free.shape)),
        cliques=cliques,
        annotator="ursim_core.synth.generator (generated ground truth)",
    )


def make_pair(
    *,
    seed: int = 0,
    shape: tuple[int, int] = (400, 512),
    n_rooms: int | None = None,
    corridor_width: int = 30,
    wall_thickness: int = 4,
    door_width: int = 10,
    **sketch_options,
) -> tuple[FloorPlan, Sketch]:
    """A plan and its sketch from one seed.

    Parameters
    ----------
    seed, shape, n_rooms, corridor_width, wall_thickness, door_width : keyword-only
        Passed to :func:`generate_floor_plan` (``seed`` to :func:`sketchify` as well).
    **sketch_options
        Passed to :func:`sketchify`.

    Examples
    --------
    >>> plan, sketch = make_pair(seed=4)
    >>> sketch.free.shape[0] > plan.free.shape[0]
    True
    """
    plan = generate_floor_plan(
        shape=shape,
        n_rooms=n_rooms,
        seed=seed,
        corridor_width=corridor_width,
        wall_thickness=wall_thickness,
        door_width=door_width,
    )
    return plan, sketchify(plan, seed=seed, **sketch_options)


def _png_bytes(free: np.ndarray) -> bytes:
    ok, encoded = cv2.imencode(".png", np.where(free, 255, 0).astype(np.uint8), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise ParameterError("could not encode the map as PNG", field="free")
    return encoded.tobytes()


def save_example(plan: FloorPlan, sketch: Sketch, folder: str | Path, *, now: str | None = None) -> None:
    """Write ``metric.png``, ``sketch.png`` (8-bit grey, 255 free, 0 wall) and ``ground_truth.json``.

    The JSON file is in the project's correspondence format
    (:func:`ursim_core.correspondences.codec.save_correspondences`), with the maps' sizes and
    SHA-256 and one clique per place present in both maps.

    Parameters
    ----------
    plan, sketch
        What to write.
    folder : str or Path
        Created if missing; the three files in it are replaced.
    now : str, optional, keyword-only
        Timestamp to record (``YYYY-MM-DDTHH:MM:SSZ``) so the output is byte-for-byte
        reproducible; the current time by default.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> save_example(*make_pair(seed=1), folder, now="2024-01-01T00:00:00Z")
    >>> sorted(p.name for p in folder.iterdir())
    ['ground_truth.json', 'metric.png', 'sketch.png']
    """
    import dataclasses

    from ursim_core.correspondences.codec import MapRef, save_correspondences
    from ursim_core.io.atomic import atomic_write_bytes

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    refs = {}
    for side, free in (("metric", plan.free), ("sketch", sketch.free)):
        data = _png_bytes(free)
        path = folder / f"{side}.png"
        atomic_write_bytes(path, data)
        refs[side] = MapRef(path=path.resolve(), sha256=hashlib.sha256(data).hexdigest(), size=tuple(free.shape))
    corr = dataclasses.replace(ground_truth_correspondences(plan, sketch), sketch=refs["sketch"], metric=refs["metric"])
    save_correspondences(corr, folder / "ground_truth.json", now=now)
