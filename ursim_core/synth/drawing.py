"""A floor plan drawn as a person might draw it from memory (:func:`sketchify`).

See ``/work/shared/design/paper.md``: a different overall scale, rooms drawn out of proportion,
slightly bent and wobbly thick walls, a small overall rotation, a dead-end corridor left out and a
corridor stub added that the building does not have. Place ids are carried through the warp with
nearest-neighbour sampling, so the ground truth stays exact.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from scipy import ndimage

from ursim_core.errors import ParameterError
from ursim_core.synth.floor_plans import FloorPlan

__all__ = ["Sketch", "sketchify"]


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

    Examples
    --------
    >>> from ursim_core.synth import generate_floor_plan
    >>> plan = generate_floor_plan(shape=(200, 300), seed=1)
    >>> sketch = sketchify(plan, seed=1)
    >>> sketch.free.shape, sketch.dropped, sketch.extra, int(sketch.rooms.max())
    ((308, 456), (5,), (12,), 12)
    >>> print(*sketch.notes, sep="\\n")
    place 5 (dead-end corridor) is not drawn
    place 12 (corridor stub, 25 x 52 px) added right of place 3
    drawn at scale 1.3 (local +-0.3), rotated +2.7 degrees
    """

    free: np.ndarray
    rooms: np.ndarray
    dropped: tuple[int, ...] = ()
    extra: tuple[int, ...] = ()
    notes: tuple[str, ...] = ()


# --------------------------------------------------------------------------- plan generation


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
    >>> from ursim_core.synth import generate_floor_plan
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
