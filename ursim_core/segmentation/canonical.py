"""Segmentation that does not depend on how the map is turned: segment in a canonical pose.

MAORIS walks the image in raster order, so the same sketch turned by 90 degrees or mirrored can
come out with another number of regions, and region ids always follow the raster order. A sketch
can be drawn in any orientation, and the user expects the same regions whichever way it lies.

:func:`canonical_labels` (and :func:`ursim_core.segmentation.segment_canonical`, the same with a
registered segmenter, or ``segment(..., params={"canonical": True})``)

1. turns the map so that its dominant wall direction is along the image axes (only when it is
   off by more than ``min_angle`` degrees: resampling costs detail), and smooths what the turn
   made (:func:`smoothed_turn`),
2. picks, among the 8 quarter turns and mirror images of that, the one whose second and third
   central moments of free space satisfy a fixed rule (:func:`canonical_pose`), the same image
   whichever of the 8 it started as,
3. segments that image, numbers the regions in its raster order, and maps the label image back
   to the map's own pixel frame (exactly for quarter turns and mirrors; nearest pixel for a
   free angle).

Points clicked on the map keep their meaning: the returned labels are in the original frame.
"""

from __future__ import annotations

import functools
import math

import numpy as np

__all__ = [
    "wall_angle",
    "canonical_pose",
    "canonical_labels",
    "dihedral",
    "turned_back",
    "smoothed_turn",
    "free_window",
    "turn_on_canvas",
    "RESAMPLING_OFFSETS",
    "TURN_SMOOTHING_DIVISOR",
]

# Contours are simplified to polygons with this tolerance (pixels) before their edge directions are
# taken: pixel staircases of a straight wall would otherwise vote for 0 and 90 degrees.
_POLYGON_TOLERANCE = 2.0
# Images larger than this (pixels) are reduced before their contours are traced: the angle of long
# walls does not need every pixel, and an 8000 x 8000 map would cost 0.1 s for nothing.
_ANGLE_MAX_PIXELS = 1_500_000
# Below this many degrees off the axes a map is not resampled: walls a few degrees off are
# how people draw, and resampling would blur thin walls for nothing.
_MIN_ANGLE = 3.0
#: The other turns back (degrees added to the wall angle) of a map that is resampled onto its wall
#: axes: MAORIS's regions change with the resampling, so the matcher votes over the answers of
#: these segmentations and of the map segmented as it is (:mod:`ursim_core.matching.resampling`).
#: Rounds 30-32 had the first four; the half degrees came in round 33 (ten segmentations, see
#: ``MatchConfig.vote_segmentations``, which votes over the first ones of this order). Round 37:
#: eight voted better than ten with the vote's new reading rule, so +0.5 and +1.5, the last two,
#: were no longer made; round 39: six, chosen held out once the turned maps were smoothed, so
#: -1.5 and -0.5 are not either (and the offsets are symmetric, as a mirrored map's are).
RESAMPLING_OFFSETS = (-2.0, -1.0, 1.0, 2.0)
#: A map resampled onto its wall axes is smoothed before it is segmented by a median filter whose
#: side is its free space's median distance to a wall divided by this (:func:`smoothed_turn`).
#: Round 38, chosen on the 18 KTH sketches turned by 15, 30, ..., 345 degrees among thirteen
#: filters (fixed sides of 3 to 11 px, morphological ones, sides of a third, a quarter and a fifth
#: of that distance, capped or not): in sample 0.7720 / 0.7702 against 0.7495 / 0.7558 unfiltered;
#: leave-one-sketch-out over all thirteen 0.7640 / 0.7596 (docs/studies.md). A quarter, uncapped,
#: because it is the same at every scale: a fixed 7 px side lost on the generated pairs.
TURN_SMOOTHING_DIVISOR = 4.0
# The median distance to a wall is taken over at most this many free pixels (evenly spaced).
_SMOOTHING_SAMPLE = 1_000_000


def wall_angle(free: np.ndarray) -> float:
    """Dominant wall direction of a map, in degrees in [-45, 45), from its free-space outline.

    The outline is traced (OpenCV contours), simplified to polygons, and each polygon edge votes
    for its direction modulo 90 degrees with a weight equal to its length (a circular mean of four
    times the angle). Angles are counter-clockwise as seen on the screen.

    Parameters
    ----------
    free : ndarray of bool or int, shape (rows, cols)
        Free space (or a label image: non-zero is free).

    Returns
    -------
    float
        0.0 for an empty map or one with no dominant direction.

    Examples
    --------
    >>> free = np.zeros((60, 80), bool); free[10:50, 10:70] = True
    >>> round(wall_angle(free), 3)
    0.0
    """
    mask = np.asarray(free) != 0
    if not mask.any():
        return 0.0
    if mask.size > _ANGLE_MAX_PIXELS:
        step = math.ceil(math.sqrt(mask.size / _ANGLE_MAX_PIXELS))
        mask = mask[::step, ::step]
    # Traced in the box around the free space (a pixel of margin kept where the image has one,
    # so that no free pixel comes to an edge it was not on): the same contours in the same
    # order, shifted, and the vote reads only differences of their points, so the same angle
    # bit for bit (a test), from a fraction of a turned sketch's padded image (round 41: 1.4
    # against 1.7-2.4 ms per KTH label image).
    import cv2

    image = np.ascontiguousarray(mask, dtype=np.uint8)
    left, top, width, height = cv2.boundingRect(image)
    first_row, first_col = max(top - 1, 0), max(left - 1, 0)
    image = image[first_row : top + height + 1, first_col : left + width + 1]
    # Remembered by content: a turned map's six segmentations each ask for the angle of the
    # same free space (and turned_back before them), and the vote below traces it eight times.
    return _voted_angle(image.tobytes(), image.shape)


@functools.lru_cache(maxsize=8)
def _voted_angle(data: bytes, shape: tuple) -> float:
    """:func:`wall_angle` of the uint8 image ``data`` of ``shape`` (non-zero is free)."""
    # Every quarter turn and mirror image of the map votes (a mirror image's vote conjugated back),
    # added exactly (fsum): then the angle of each of the 8 copies of a map is exactly the map's,
    # or its negation. Tracing and simplifying one outline alone is not exactly equivariant: the
    # copies of a generated sketch came out up to 0.13 degrees apart, and were resampled apart.
    import cv2

    image = np.frombuffer(data, dtype=np.uint8).reshape(shape)
    # dihedral(mask, quarter_turns, mirrored), made by OpenCV: a quarter of numpy's copy time.
    rotations = {1: cv2.ROTATE_90_COUNTERCLOCKWISE, 2: cv2.ROTATE_180, 3: cv2.ROTATE_90_CLOCKWISE}
    votes = []
    for quarter_turns in range(4):
        turned = cv2.rotate(image, rotations[quarter_turns]) if quarter_turns else image
        votes.append(_outline_vote(turned))
        votes.append(_outline_vote(cv2.flip(turned, 1)).conjugate())
    total = complex(math.fsum(vote.real for vote in votes), math.fsum(vote.imag for vote in votes))
    if abs(total) < 1e-9:
        return 0.0
    # In (-45, 45] from the angle's range; only 45 is wrapped, so that a mirror image's is exactly
    # the negation (adding and taking 45 again would round).
    degrees = math.degrees(math.atan2(total.imag, total.real) / 4)
    return -45.0 if degrees >= 45.0 else degrees


def _outline_vote(image: np.ndarray) -> complex:
    """Sum over the edges of the simplified outlines of ``image`` (uint8, non-zero is free) of
    length x exp(4i x direction)."""
    import cv2

    contours, _ = cv2.findContours(image, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    polygons = [cv2.approxPolyDP(contour, _POLYGON_TOLERANCE, True).reshape(-1, 2) for contour in contours]
    polygons = [polygon for polygon in polygons if len(polygon) >= 2]
    if not polygons:
        return 0j
    # Every polygon's edges at once: each vertex's successor is the next one, the last vertex's
    # the polygon's first. (A building-sized map has thousands of outlines, and NumPy calls per
    # outline took 0.06 of the 0.08 s per image; the sum is the same up to rounding, and the
    # vote stays a function of the image alone, so the eight copies still vote alike.)
    points = np.concatenate(polygons).astype(np.float64)
    successor = np.arange(1, len(points) + 1)
    ends = np.cumsum([len(polygon) for polygon in polygons])
    successor[ends - 1] = np.concatenate(([0], ends[:-1]))
    edges = points[successor] - points
    dx, dy_up = edges[:, 0], -edges[:, 1]
    return complex((np.hypot(dx, dy_up) * np.exp(4j * np.arctan2(dy_up, dx))).sum())


def dihedral(image: np.ndarray, quarter_turns: int, mirrored: bool) -> np.ndarray:
    """``image`` turned counter-clockwise by ``quarter_turns`` x 90 degrees, then mirrored left-right.

    Examples
    --------
    >>> dihedral(np.array([[1, 2], [3, 4]]), 1, False).tolist()
    [[2, 4], [1, 3]]
    >>> dihedral(np.array([[1, 2], [3, 4]]), 0, True).tolist()
    [[2, 1], [4, 3]]
    """
    out = np.rot90(image, quarter_turns % 4)
    if mirrored:
        out = out[:, ::-1]
    return np.ascontiguousarray(out)


def _undo_dihedral(image: np.ndarray, quarter_turns: int, mirrored: bool) -> np.ndarray:
    out = image[:, ::-1] if mirrored else image
    return np.ascontiguousarray(np.rot90(out, -(quarter_turns % 4)))


def _moments(free: np.ndarray, window: tuple[slice, slice] | None = None) -> tuple[float, float, float, float]:
    """Variance and third central moment of the free pixels' rows and columns.

    From the row and column counts (two sums over the image, then 1-D sums), not from the
    pixel coordinates: a few milliseconds on a 2-million-pixel sketch instead of about 50.
    ``window``: a box outside which ``free`` has no free pixel; the counts are summed in it and
    set in arrays of the image's length, so the 1-D sums are those of the whole image, bit for bit.
    """
    values = []
    for axis in (1, 0):
        if window is None:
            counts = free.sum(axis=axis, dtype=np.float64)
        else:
            counts = np.zeros(free.shape[1 - axis], np.float64)
            counts[window[1 - axis]] = free[window].sum(axis=axis, dtype=np.float64)
        total = counts.sum()
        if total == 0:
            return 0.0, 0.0, 0.0, 0.0
        position = np.arange(counts.size, dtype=np.float64)
        centred = position - (position * counts).sum() / total
        values.append((float((centred**2 * counts).sum() / total), float((centred**3 * counts).sum() / total)))
    (var_r, skew_r), (var_c, skew_c) = values
    return var_r, var_c, skew_r, skew_c


def _turned_moments(var_r, var_c, skew_r, skew_c, quarter_turns: int, mirrored: bool):
    """The second and third central moments of ``dihedral(free, quarter_turns, mirrored)``.

    Examples
    --------
    >>> free = np.zeros((30, 40), bool); free[2:10, 2:38] = True; free[10:28, 2:8] = True
    >>> all(
    ...     np.allclose(_turned_moments(*_moments(free), k, m), _moments(dihedral(free, k, m)))
    ...     for k in range(4) for m in (False, True)
    ... )
    True
    """
    for _ in range(quarter_turns % 4):
        var_r, var_c, skew_r, skew_c = var_c, var_r, -skew_c, skew_r
    if mirrored:
        skew_c = -skew_c
    return var_r, var_c, skew_r, skew_c


def canonical_pose(free: np.ndarray, *, window: tuple[slice, slice] | None = None) -> tuple[int, bool]:
    """The quarter turns and mirroring that bring ``free`` to its canonical pose.

    Canonical: free space spreads at least as much along the columns as along the rows, and its
    third central moment is non-negative along both axes (more mass towards the top-left, a tail
    towards the bottom-right). Every quarter turn or mirror image of a map has the same canonical
    image; exact ties (a symmetric map) go to the first pose in a fixed order. ``window``: a box
    outside which ``free`` has no free pixel (:func:`free_window`), to sum over only that.

    Examples
    --------
    >>> free = np.zeros((30, 40), bool); free[2:10, 2:38] = True; free[10:28, 2:8] = True
    >>> pose = canonical_pose(free)
    >>> all(
    ...     np.array_equal(dihedral(dihedral(free, k, m), *canonical_pose(dihedral(free, k, m))), dihedral(free, *pose))
    ...     for k in range(4) for m in (False, True)
    ... )
    True
    """
    free = np.asarray(free) != 0
    # The central moments of every pose follow from the map's own: a quarter turn maps the
    # centred (r, c) to (-c, r), a mirror c to -c. One pass over the pixels instead of eight.
    var_r0, var_c0, skew_r0, skew_c0 = _moments(free, window)
    best_key, best = None, (0, False)
    for mirrored in (False, True):
        for quarter_turns in range(4):
            var_r, var_c, skew_r, skew_c = _turned_moments(var_r0, var_c0, skew_r0, skew_c0, quarter_turns, mirrored)
            # Round so that the same moments computed from a turned copy compare equal.
            key = (
                var_c >= var_r - 1e-9 * max(var_c, var_r, 1.0),
                skew_r >= -1e-9,
                skew_c >= -1e-9,
                round(skew_r, 6),
                round(skew_c, 6),
            )
            if best_key is None or key > best_key:
                best_key, best = key, (quarter_turns, mirrored)
    return best


def _renumber(labels: np.ndarray, window: tuple[slice, slice] | None = None) -> np.ndarray:
    """Region ids (non-negative) made consecutive (1..N) in their old order; 0 stays 0.

    By a table indexed by id, not :func:`numpy.unique`: its sort of every pixel took 0.6 of the
    0.7 s of each of the six segmentations of a KTH sketch turned by 30 degrees (its canvas of 3.4
    million pixels, round 57); the table takes milliseconds and gives the same ids.
    ``window``: a box outside which every label is 0; only it is read and renumbered (in place).

    Examples
    --------
    >>> _renumber(np.array([[0, 7, 7], [3, 0, 9]])).tolist()
    [[0, 2, 2], [1, 0, 3]]
    """
    labels = np.asarray(labels)
    if labels.size == 0:
        return labels.astype(np.int32)
    inner = labels if window is None else labels[window]
    present = np.bincount(inner.ravel()) > 0
    if inner.size < labels.size:
        present[0] = True  # the pixels outside the window
    table = np.cumsum(present, dtype=np.int32)  # the rank among the ids present, from 1
    if present[0]:
        table -= 1  # 0 is present: it keeps 0 and the others count from 1
    if window is None:
        return table[labels]
    labels = labels.astype(np.int32, copy=False)
    labels[window] = table[inner]
    return labels


def free_window(free: np.ndarray, margin: int = 0) -> tuple[slice, slice] | None:
    """The box of ``free``'s free pixels grown by ``margin`` on every side (clipped to the
    image), as a pair of slices; None when it has no free pixel. MAORIS works in
    ``free_window(free, 1)`` (:func:`~ursim_core.segmentation.maoris.maoris_labels`).

    Examples
    --------
    >>> free = np.zeros((5, 6), bool); free[1:3, 2:4] = True
    >>> free_window(free, 1)
    (slice(0, 4, None), slice(1, 5, None))
    """
    rows, cols = np.flatnonzero(free.any(axis=1)), np.flatnonzero(free.any(axis=0))
    if rows.size == 0:
        return None
    return _grown((slice(int(rows[0]), int(rows[-1]) + 1), slice(int(cols[0]), int(cols[-1]) + 1)), margin, free.shape)


def _grown(window: tuple[slice, slice], margin: int, shape: tuple[int, ...]) -> tuple[slice, slice]:
    """``window`` grown by ``margin`` on every side, clipped to an image of ``shape``."""
    rows, cols = window
    return (
        slice(max(0, rows.start - margin), min(shape[0], rows.stop + margin)),
        slice(max(0, cols.start - margin), min(shape[1], cols.stop + margin)),
    )


def turn_on_canvas(shape: tuple[int, int], degrees: float) -> tuple[np.ndarray, tuple[int, int]]:
    """The OpenCV affine map that turns an image of ``shape`` counter-clockwise by ``degrees`` about
    its centre onto a canvas that holds all of it, and that canvas's ``(rows, cols)``.

    Examples
    --------
    >>> matrix, canvas = turn_on_canvas((10, 20), 45.0)
    >>> canvas
    (22, 22)
    """
    import cv2

    rows, cols = shape
    theta = math.radians(degrees)
    c, s = abs(math.cos(theta)), abs(math.sin(theta))
    new_cols, new_rows = int(math.ceil(cols * c + rows * s)), int(math.ceil(cols * s + rows * c))
    matrix = cv2.getRotationMatrix2D(((cols - 1) / 2, (rows - 1) / 2), degrees, 1.0)
    matrix[0, 2] += (new_cols - cols) / 2
    matrix[1, 2] += (new_rows - rows) / 2
    return matrix, (new_rows, new_cols)


def _turned(free: np.ndarray, degrees: float) -> tuple[np.ndarray, np.ndarray]:
    """``free`` turned counter-clockwise by ``degrees`` on a canvas that holds it, and the affine map."""
    import cv2

    matrix, (new_rows, new_cols) = turn_on_canvas(free.shape, degrees)
    image = cv2.warpAffine(
        free.astype(np.uint8) * 255, matrix, (new_cols, new_rows), flags=cv2.INTER_LINEAR, borderValue=0
    )
    return image >= 128, matrix


def smoothed_turn(free: np.ndarray, *, divisor: float = TURN_SMOOTHING_DIVISOR) -> np.ndarray:
    """``free``, a map just resampled onto its wall axes, under a median filter whose side is its
    free space's median distance to a wall divided by ``divisor`` (the odd number at or below;
    no filter below 3 px).

    The turn leaves steps of a pixel or two along walls that were straight, and together with the
    pen's own wobble they make MAORIS split rooms, or join them, where the map as drawn does not.
    The side follows the size of the rooms, so a map drawn at twice the scale is smoothed alike,
    and thin corridors of a small map are not filtered away.

    Examples
    --------
    >>> free = np.zeros((140, 180), bool); free[20:120, 20:160] = True
    >>> free[70, 160] = True  # a one-pixel spur on a straight wall
    >>> smoothed = smoothed_turn(free)
    >>> bool(smoothed[70, 160]), bool(smoothed[70, 90])  # the spur goes, the room stays
    (False, True)
    >>> int(free.sum() - smoothed.sum())  # the spur and the four corner pixels (a 3 x 3 filter)
    5
    """
    import cv2

    free = np.asarray(free) != 0
    box = free_window(free)
    if box is None:
        return free
    # Worked within the free space's box and a margin: a turned map's canvas is mostly empty.
    # A margin of one keeps every distance to a wall; the filter's side keeps what it changes.
    inside = free[_grown(box, 1, free.shape)]
    distances = cv2.distanceTransform(inside.astype(np.uint8), cv2.DIST_L2, 5)[inside]
    if distances.size > _SMOOTHING_SAMPLE:
        distances = distances[:: distances.size // _SMOOTHING_SAMPLE]
    side = int(float(np.median(distances)) / divisor)
    side = side if side % 2 else side - 1
    if side < 3:
        return free
    window = _grown(box, side, free.shape)
    smoothed = np.zeros_like(free)
    smoothed[window] = cv2.medianBlur(free[window].astype(np.uint8) * 255, side) >= 128
    return smoothed


def turned_back(free: np.ndarray, *, min_angle: float = _MIN_ANGLE) -> bool:
    """Whether :func:`canonical_labels` resamples ``free`` onto its wall axes (its walls are at
    least ``min_angle`` degrees off the image axes).

    Examples
    --------
    >>> free = np.zeros((60, 80), bool); free[10:50, 10:70] = True
    >>> turned_back(free)
    False
    """
    return abs(wall_angle(np.asarray(free) != 0)) >= min_angle


def canonical_labels(
    free: np.ndarray,
    labels_of,
    *,
    min_angle: float = _MIN_ANGLE,
    turn_offset: float | None = 0.0,
    free_box_only: bool = False,
) -> np.ndarray:
    """Label ``free`` in its canonical pose with ``labels_of`` and bring the labels back.

    ``labels_of(free) -> labels`` is any segmenter on a free-space mask. The result is in
    ``free``'s own pixel frame, ids 1..N in the raster order of the canonical image, so every
    quarter turn or mirror image of a map gets the same regions with the same ids.
    ``min_angle``: the smallest wall-direction offset, in degrees, for which the map is turned
    before it is labelled. ``turn_offset``: degrees added to that turn (one of the other
    resamplings of :data:`RESAMPLING_OFFSETS`); None labels the map as it is, without the turn.
    A map that is not turned is labelled the same whatever the offset.
    ``free_box_only``: ``labels_of`` gives 0 outside the box of a mask's free pixels and the same
    labels for any mask that has that box and a margin of a pixel (MAORIS works on that box), so
    it is given only that part of the canonical image, and only it is turned back and numbered: the
    same labels without passes over a turned map's canvas, mostly empty (a KTH sketch turned by
    30 degrees: 6.8 million pixels for 0.3 million free).
    :func:`ursim_core.segmentation.segment_canonical` is this with a registered segmenter.

    Examples
    --------
    >>> free = np.zeros((100, 170), bool)  # a large and a small room joined by a corridor
    >>> free[10:90, 10:70] = free[30:70, 100:150] = free[45:55, 70:100] = True
    >>> first_column = lambda f: (np.cumsum(f, axis=1) == 1).astype(np.int32)  # any labelling
    >>> a = canonical_labels(free, first_column)
    >>> np.array_equal(np.rot90(a), canonical_labels(np.rot90(free), first_column))
    True
    """
    import cv2

    free = np.asarray(free) != 0
    angle = wall_angle(free)
    if abs(angle) < min_angle or turn_offset is None:
        work, matrix = free, None
    else:
        work, matrix = _turned(free, -(angle + turn_offset))
        work = smoothed_turn(work)
    window = free_window(work, 1) if free_box_only else None
    if free_box_only and window is None:
        return np.zeros(free.shape, np.int32)
    quarter_turns, mirrored = canonical_pose(work, window=window)
    pose = work if window is None else work[window]
    labels = _undo_dihedral(
        np.asarray(labels_of(dihedral(pose, quarter_turns, mirrored)), dtype=np.int32), quarter_turns, mirrored
    )
    if window is not None:
        # Set back in an image of the canonical image's size: the turn back below then samples
        # the same values at the same places.
        whole = np.zeros(work.shape, np.float32 if matrix is not None else np.int32)
        whole[window] = labels
        labels = whole
    if matrix is None:
        return labels
    inverse = cv2.invertAffineTransform(matrix)
    back = cv2.warpAffine(
        labels.astype(np.float32, copy=False),
        inverse,
        (free.shape[1], free.shape[0]),
        flags=cv2.INTER_NEAREST,
        borderValue=0,
    )
    if window is None:
        labels = back.astype(np.int32)
        labels[~free] = 0
        return _renumber(labels)
    # Only the free pixels keep a label; they lie in their box.
    box = free_window(free)
    labels = np.zeros(free.shape, np.int32)
    if box is not None:
        labels[box] = np.where(free[box], back[box], 0)
    return _renumber(labels, box)
