"""The exact Euclidean distance transform of MAORIS step 1 (numba; the reference of ``csrc/distance.c``).

``cv2.distanceTransform(free, DIST_L2, DIST_MASK_PRECISE)`` gives the same floats, but its first
pass walks down each column: at 8000 x 8000 px a column's 8000 rows are 8000 cache lines, and that
pass grew x4.8 for x4 pixels from 4000 px (0.10 -> 0.48 s) on the development machine. Here both
passes go along rows (Felzenszwalb and Huttenlocher 2012, "Distance transforms of sampled
functions"):

1. for every pixel, the distance along its column to the nearest obstacle (0) pixel, found by one
   sweep down and one up the image, each row at a time (all columns of a row at once);
2. for every row, the lower envelope of the parabolas ``(x - q)^2 + g(q)^2`` of its pixels q, read
   off at every x: the squared distance to the nearest obstacle, an integer.

The envelope's breakpoints are compared as exact fractions of 64-bit integers (sides below
2**20 px), so the squared distances are exact and the result is ``sqrt`` of each, correctly
rounded to float32. OpenCV's floats are at times an ulp or two off (its breakpoints are products
with rounded inverses), never across an integer in the tests: the radii ``int(distance)``, all
that MAORIS reads of them, are the same. As in OpenCV, outside the image is not an obstacle, and
an image with no obstacle pixel at all gets 2**64 everywhere.

The column distances are kept in ``out``'s own memory (read as int32, a row of them copied out
before the row's distances are written over it): a separate image would be 256 MB of fresh memory
at 8000 x 8000 px.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: The distance given to every pixel of an image without any obstacle pixel (OpenCV's 2**64).
NO_OBSTACLE = np.float32(2.0**64)

#: Sides of at least this many pixels overflow the breakpoints' 64-bit products.
MAX_SIDE = 1 << 20


@njit(cache=True)
def distance_transform(free, out):
    """Euclidean distance of every pixel of ``free`` (uint8, 0 = obstacle) to the nearest
    obstacle pixel, written to ``out`` (float32, C-contiguous, the same shape).

    Raises ValueError for a side of :data:`MAX_SIDE` px or more.
    """
    rows, cols = free.shape
    if out.shape[0] != rows or out.shape[1] != cols:
        raise ValueError("distance_transform: free and out differ in shape")
    if rows >= MAX_SIDE or cols >= MAX_SIDE:
        raise ValueError("distance_transform: a side of 2**20 px or more")
    if rows == 0 or cols == 0:
        return
    column = out.view(np.int32)  # -1: no obstacle in that direction of the column
    # Pass 1, down: the distance to the nearest obstacle at or above each pixel.
    for col in range(cols):
        column[0, col] = -1 if free[0, col] else 0
    for row in range(1, rows):
        for col in range(cols):
            above = column[row - 1, col]
            column[row, col] = 0 if not free[row, col] else (-1 if above < 0 else above + 1)
    # ... then up: the nearer of that and the nearest obstacle below.
    for row in range(rows - 2, -1, -1):
        for col in range(cols):
            below = column[row + 1, col]
            here = column[row, col]
            if below >= 0 and (here < 0 or below + 1 < here):
                column[row, col] = below + 1
    # Pass 2, along each row: the lower envelope of the finite parabolas.
    squared = np.empty(cols, np.int64)
    vertex = np.empty(cols, np.int64)
    start_num = np.empty(cols + 1, np.int64)  # where vertex k's parabola starts to be lowest:
    start_den = np.empty(cols + 1, np.int64)  # start_num[k] / start_den[k] (k >= 1)
    for row in range(rows):
        for col in range(cols):
            g = np.int64(column[row, col])
            squared[col] = g * g if g >= 0 else -1
        last = -1  # index of the envelope's last parabola
        for q in range(cols):
            if squared[q] < 0:
                continue
            num, den = np.int64(0), np.int64(1)
            while last >= 0:
                p = vertex[last]
                num = (squared[q] + q * q) - (squared[p] + p * p)
                den = 2 * (q - p)
                # The new parabola is lowest from num / den on; the last one is hidden when that
                # is at or before where the last one starts (the first one starts at -infinity).
                if last > 0 and num * start_den[last] <= start_num[last] * den:
                    last -= 1
                else:
                    break
            last += 1
            vertex[last] = q
            start_num[last], start_den[last] = num, den
        if last < 0:  # no obstacle in the whole image
            for col in range(cols):
                out[row, col] = NO_OBSTACLE
            continue
        k = 0
        for x in range(cols):
            while k < last and start_num[k + 1] < x * start_den[k + 1]:
                k += 1
            offset = x - vertex[k]
            out[row, x] = np.sqrt(np.float32(squared[vertex[k]] + offset * offset))
