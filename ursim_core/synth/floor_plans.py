"""Generated office floor plans with a place id on every free pixel.

A floor plan is an office building made of horizontal corridors (one per "band" of the building)
lined with rooms on both sides, and vertical corridors at one or both ends (and, in wide buildings,
in between) that cross them. Every free pixel carries the id of the *place* it belongs to: each
room, each corridor segment between two crossings, each crossing and each dead-end corridor is a
place. Door pixels (the gap in the wall) belong to the room, so every free pixel has exactly one
place. Also the large buildings of the scale benchmark (:func:`make_large_building`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import networkx as nx
import numpy as np

from ursim_core.errors import ParameterError

__all__ = ["Place", "FloorPlan", "generate_floor_plan", "make_large_building", "interior_points"]


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

    Examples
    --------
    >>> plan = generate_floor_plan(shape=(200, 300), seed=1)
    >>> corridor = plan.places[0]
    >>> corridor
    Place(id=1, kind='corridor', role='segment', interior=(99, 149))
    >>> int(plan.rooms[corridor.interior]) == corridor.id  # the interior point lies in the place
    True
    >>> sorted({place.role for place in plan.places})
    ['crossing', 'dead end', 'room', 'segment']
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

    Examples
    --------
    >>> plan = generate_floor_plan(shape=(200, 300), seed=1)
    >>> plan.free.shape, len(plan.places), plan.params["corridor_width"]
    ((200, 300), 11, 30)
    >>> plan.kinds[8], plan.graph.edges[1, 8]["via"]  # room 8 opens onto corridor 1 through a door
    ('room', 'door')
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
