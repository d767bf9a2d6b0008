"""Compiled kernels of the MAORIS inscribed-circle image (numba).

Step 1 of MAORIS paints, for every free pixel q with radius r = r(q), the
lattice disc ``{o : |o|^2 <= (r - 1)^2}`` centred at q - (1, 1), and keeps the
largest radius painted on each free pixel. Only the centres that no neighbour
dominates matter, but a 4000 x 4000 px building still has ~400 000 of them and
their discs add up to ~60 times the image: painting them one by one (one
``cv2.circle`` call each) cost about 1.7 s of CPU. Here the work is about
the number of pixel runs of the result plus the number of pixels (about
0.1 s at that size):

* equal-radius centres that form a rectangle of whole row runs (room ridges
  are horizontal runs, corridor ridges vertical ones) are one shape: on each
  image row its discs form one span, as wide as the disc row at the distance
  from that row to the rectangle;
* almost all other centres are lone pixels on the diagonal chains of room
  corners, where the radius grows by one at each diagonal step. The disc of
  such a diagonal neighbour (radius r + 1, reach R + 1 for this disc's reach
  R) covers every row of this disc on its own side: at distance d >= 1 from
  this centre, its row is d - 1 from its own centre, and for this row's
  half-width w (w^2 <= R^2 - d^2, w <= R) (R + 1)^2 - (d - 1)^2 =
  R^2 - d^2 + 2R + 2d >= w^2 + 2w + 2 > (w + 1)^2, so its row is wider by at
  least one on each side. On the other side it covers most of each row too:
  a table gives, per reach, the few pixels it leaves
  (:func:`_uncovered_pieces`), and only those are painted. Leaving out
  pixels that the disc of a free pixel with a larger radius covers does not
  change the maximum: by induction from the largest radius down, each of
  them gets at least that larger radius;
* each pixel keeps the maximum of the radii painted on it, so the shapes are
  painted in the raster order they are found in, which keeps the rows being
  painted in cache; obstacle pixels are set back to 0 at the end.

Half-widths ``isqrt(R^2 - d^2)`` come from integer arithmetic only, so the
result is bit for bit that of painting every disc
(:func:`ursim_core.segmentation.maoris.inscribed_circle.inscribed_circle_radii`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.helpers import inner_kernel, loop_helper

# Columns of the shape table returned by :func:`centre_rectangles`.
TOP, BOTTOM, LEFT, RIGHT, RADIUS, DIAGONALS = range(6)
# Bits of the DIAGONALS column: the diagonal neighbours (row step, column step)
# whose radius is r + 1.
_UP_LEFT, _UP_RIGHT, _DOWN_LEFT, _DOWN_RIGHT = 1, 2, 4, 8
_ABOVE, _BELOW = _UP_LEFT | _UP_RIGHT, _DOWN_LEFT | _DOWN_RIGHT


@njit(cache=True)
def centre_rectangles(dist, max_radius):
    """Non-dominated disc centres, grouped into rectangles of equal radius.

    Parameters
    ----------
    dist : ndarray of float32, shape (rows, cols)
        Euclidean distance transform (0 on obstacles); outside the array
        counts as obstacle for the domination test.
    max_radius : int
        Cap on the radius, < 2**31: r = min(int(dist), max_radius).

    Returns
    -------
    ndarray of int64, shape (n, 6)
        (top row, bottom row, left column, right column, radius, diagonals)
        of each rectangle, in raster order of their top-left pixel. Every
        rectangle is a vertical stack of identical maximal row runs of centres
        (a run is maximal among the centres of its row with the same radius).
        ``diagonals`` has the bits ``_UP_LEFT`` ... ``_DOWN_RIGHT`` of the
        diagonal neighbours with radius r + 1 of a one-pixel rectangle, and is
        0 for the others.
    """
    rows, cols = dist.shape
    # Radii of rows y - 1, y, y + 1 at slots (row % 3), with a zero column on each side.
    ring = np.zeros((3, cols + 2), np.int32)
    _load_radii(dist, np.int64(0), max_radius, ring[0])  # not a literal: one compile of it
    centre_radius = np.zeros(cols + 1, np.int32)  # 0 = not a centre; one zero past the end
    # The rectangle whose last run starts at this column (it continues only if that run is on the row above).
    open_at = np.empty(cols, np.int64)
    for col in range(cols):
        open_at[col] = -1
    shapes = np.empty((max(16, rows * cols // 64), 6), np.int64)
    count = 0
    for row in range(rows):
        up, here, down = ring[(row + 2) % 3], ring[row % 3], ring[(row + 1) % 3]
        if row + 1 < rows:
            _load_radii(dist, row + 1, max_radius, down)
        else:
            for i in range(cols + 2):
                down[i] = 0
        for col in range(cols):
            radius = here[col + 1]
            # Integer radii: a 4-neighbour's disc contains this one when its radius
            # is >= r + 1, a diagonal neighbour's when >= r + 2 (sqrt(2) rounded up).
            # Branch-free, so that the loop vectorises.
            side = max(max(here[col], here[col + 2]), max(up[col + 1], down[col + 1]))
            corner = max(max(up[col], up[col + 2]), max(down[col], down[col + 2]))
            centre_radius[col] = radius if (radius > 0) & (side <= radius) & (corner <= radius + 1) else 0
        if count + cols > len(shapes):
            # Grown here, not per run: a reassignment inside the run loop slows it fourfold.
            shapes = _grown(shapes, 2 * len(shapes) + cols)
        col = 0
        while col < cols:
            radius = centre_radius[col]
            if radius == 0:
                col += 1
                continue
            last = col
            while centre_radius[last + 1] == radius:
                last += 1
            shape = open_at[col]
            if (
                shape >= 0
                and shapes[shape, BOTTOM] == row - 1
                and shapes[shape, RIGHT] == last
                and shapes[shape, RADIUS] == radius
            ):
                shapes[shape, BOTTOM] = row
                shapes[shape, DIAGONALS] = 0
            else:
                shapes[count, TOP] = row
                shapes[count, BOTTOM] = row
                shapes[count, LEFT] = col
                shapes[count, RIGHT] = last
                shapes[count, RADIUS] = radius
                diagonals = 0
                if last == col:
                    larger = radius + 1
                    diagonals = (
                        (up[col] == larger) * _UP_LEFT
                        + (up[col + 2] == larger) * _UP_RIGHT
                        + (down[col] == larger) * _DOWN_LEFT
                        + (down[col + 2] == larger) * _DOWN_RIGHT
                    )
                shapes[count, DIAGONALS] = diagonals
                open_at[col] = count
                count += 1
            col = last + 1
    return shapes[:count]


@loop_helper
def _load_radii(dist, row, max_radius, into):
    for col in range(dist.shape[1]):
        value = dist[row, col]
        into[col + 1] = max_radius if value >= max_radius else np.int32(value)


@inner_kernel
def _grown(shapes, capacity):
    grown = np.empty((capacity, shapes.shape[1]), shapes.dtype)
    for i in range(shapes.shape[0]):
        for j in range(shapes.shape[1]):
            grown[i, j] = shapes[i, j]
    return grown


@njit(cache=True)
def paint_discs(shapes, free, out):
    """Raise each free pixel to the largest radius of the shapes' discs covering it.

    Parameters
    ----------
    shapes : ndarray of int64, shape (n, 6)
        Rectangles of :func:`centre_rectangles`, in raster order (any order
        gives the same result; this one keeps the rows being painted in cache).
    free : ndarray of uint8, shape (rows, cols), any strides
        Non-zero on free pixels: the others (obstacles) end up 0.
    out : ndarray of int32, shape (rows, cols), zeros
        Receives, on each free pixel, the largest radius whose disc (radius
        r - 1, centred at (row - 1, col - 1) for each centre of a shape)
        covers it. It may share memory with the distance transform the shapes
        came from, which is not read here (at 8000 px a fresh 256 MB image cost
        more in page faults than painting it).
    """
    rows, cols = out.shape
    # Capping the reach here changes nothing: a disc that reaches this far covers
    # every image row it meets from end to end, as the capped one does.
    reach_cap = rows + cols
    trimmed_reach_limit = min(_TRIMMED_REACH_LIMIT, reach_cap)
    largest_trimmed = np.int64(-1)  # typed, not a literal: a literal argument compiles a callee twice
    for i in range(len(shapes)):
        if shapes[i, DIAGONALS] != 0 and shapes[i, RADIUS] - 1 < trimmed_reach_limit:
            largest_trimmed = max(largest_trimmed, shapes[i, RADIUS] - 1)
    piece_start, piece_distance, piece_from, piece_to = _uncovered_pieces(largest_trimmed)
    for i in range(len(shapes)):
        radius = shapes[i, RADIUS]
        reach = min(radius - 1, reach_cap)
        # The discs are centred one row up and one column left of the centres.
        top, bottom = shapes[i, TOP] - 1, shapes[i, BOTTOM] - 1
        left, right = shapes[i, LEFT] - 1, shapes[i, RIGHT] - 1
        diagonals = shapes[i, DIAGONALS] if reach < trimmed_reach_limit else 0
        if diagonals == 0:
            # Whole disc rows; the half-width follows the distance d to the shape's rows
            # (down to 0, then up again) in integer steps.
            width = 0
            for row in range(top - reach, bottom + reach + 1):
                d = max(top - row, row - bottom, 0)
                while (width + 1) * (width + 1) + d * d <= reach * reach:
                    width += 1
                while width * width + d * d > reach * reach:
                    width -= 1
                if 0 <= row < rows:
                    _raise_span(out, row, left - width, right + width, radius)
            continue
        # A one-pixel shape with diagonal neighbours of radius r + 1 below (else above):
        # the pieces of its own row and of the rows above (below) that their discs leave
        # uncovered. They cover the rows on their side, so with neighbours on both sides
        # only its own row is left.
        below = diagonals & _BELOW != 0
        step = -1 if below else 1
        neighbours = diagonals >> 2 if below else diagonals & _ABOVE
        farthest = 0 if diagonals & _ABOVE and below else reach
        key = reach * 3 + neighbours
        for piece in range(piece_start[key - 1], piece_start[key]):
            if piece_distance[piece] > farthest:
                break
            row = top + step * piece_distance[piece]
            if 0 <= row < rows:
                _raise_span(out, row, left + piece_from[piece], left + piece_to[piece], radius)
    for row in range(rows):
        for col in range(cols):
            if free[row, col] == 0:
                out[row, col] = 0


# One-pixel shapes up to this reach paint only what their diagonal neighbours leave
# uncovered (the table has room for 3 R^2 pieces); larger ones, if any, paint their whole disc.
_TRIMMED_REACH_LIMIT = 512


@loop_helper
def _raise_span(out, row, first_col, last_col, radius):
    for col in range(max(first_col, 0), min(last_col, out.shape[1] - 1) + 1):
        out[row, col] = max(out[row, col], radius)


@inner_kernel
def _uncovered_pieces(largest_reach):
    """What the diagonal neighbours (radius r + 1) of a one-pixel shape leave of its disc.

    For a disc of reach R whose diagonal neighbours are all on one side, k
    saying which (bit 1: the left one, bit 2: the right one, as
    ``_UP_LEFT``/``_UP_RIGHT`` or ``_DOWN_LEFT``/``_DOWN_RIGHT`` shifted
    down), ``piece_start[3R + k - 1]:piece_start[3R + k]`` are the pieces
    (d, from, to): the columns from..to, relative to the centre, of the row
    at distance d = 0..R on the other side that no neighbour's disc covers,
    by increasing d. A neighbour's row there is d + 1 from its centre, so it
    is as wide as the row d + 1 away in a disc of reach R + 1. The rows on the
    neighbours' side need no pieces (proof in the module docstring).

    Parameters
    ----------
    largest_reach : int
        Largest R in the table; -1 for an empty one.

    Returns
    -------
    piece_start : ndarray of int64, shape (3 (largest_reach + 1) + 1,)
    piece_distance, piece_from, piece_to : ndarray of int32
    """
    # Half-widths isqrt(R^2 - d^2) at half_width[R (R + 1) / 2 + d], up to R + 1.
    half_width = np.empty((largest_reach + 2) * (largest_reach + 3) // 2, np.int64)
    for reach in range(largest_reach + 2):
        width = reach
        for d in range(reach + 1):
            while width * width + d * d > reach * reach:
                width -= 1
            half_width[reach * (reach + 1) // 2 + d] = width
    piece_start = np.zeros(3 * (largest_reach + 1) + 1, np.int64)
    capacity = 6 * (largest_reach + 1) * (largest_reach + 2) // 2
    piece_distance = np.empty(capacity, np.int32)
    piece_from = np.empty(capacity, np.int32)
    piece_to = np.empty(capacity, np.int32)
    count = 0
    for reach in range(largest_reach + 1):
        for neighbours in range(1, 4):
            for d in range(reach + 1):
                width = half_width[reach * (reach + 1) // 2 + d]
                covering = half_width[(reach + 1) * (reach + 2) // 2 + d + 1]
                covered_from = (-1 if neighbours & 1 else 1) - covering
                covered_to = (1 if neighbours & 2 else -1) + covering
                # The columns left of the covered ones, then those right of them.
                left_piece = (-width, min(width, covered_from - 1))
                right_piece = (max(-width, covered_to + 1), width)
                for first, last in (left_piece, right_piece):
                    if first <= last:
                        piece_distance[count] = d
                        piece_from[count] = first
                        piece_to[count] = last
                        count += 1
            piece_start[3 * reach + neighbours] = count
    return piece_start, piece_distance, piece_from, piece_to


@njit(cache=True)
def lookup_bytes(values, lo, table, out):
    """``out[p] = table[values[p] - lo]`` for every pixel p of an int32 image (MAORIS step 2:
    the radii mapped to the value image); IndexError when a value is outside the table."""
    for row in range(values.shape[0]):
        for col in range(values.shape[1]):
            index = values[row, col] - lo
            if index < 0 or index >= len(table):
                raise IndexError("lookup_bytes: a value is outside lo .. lo + len(table) - 1")
            out[row, col] = table[index]
