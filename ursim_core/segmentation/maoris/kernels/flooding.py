"""Compiled marker flooding of the clearance watershed: scikit-image's priority flood, exactly.

:func:`flood_levels` pops pixels in the order of ``skimage.segmentation.watershed``
(``_watershed_cy.watershed_raveled`` without compactness or watershed lines, 0.26):
a binary min-heap of (value, age) whose markers enter first, in raster order, with age 0,
and whose every pushed neighbour gets the next age; a pixel takes its label when it is
pushed, from the pixel whose pop pushed it, and its value is raised to that pixel's.
Ages are unique but for the markers, so only the order among markers of one value depends
on the heap's own arrangement: this heap makes the same comparisons and the same moves
as scikit-image's (``heap_general.pxi``), hence pops equal markers in the same order.

Why a heap and not a bucket queue per value (FIFO on ages): the pop order of equal
markers depends on where the whole history left them in the heap, and it changes labels
(two rooms of the same width meet in the door at the same time).

Speed, for the same moves: an entry is one ``uint64``, ``level | age | pixel`` (the level
is the rank of the value), compared without its pixel bits, so equal markers compare
equal as they do there; a pop descends along the smaller children to a leaf (one
comparison a level, left child on ties) and climbs back while the element moved up is
not smaller than the last entry, which leaves every entry where scikit-image's sift-down
leaves it; the node is kept one slot off so that siblings share a cache line.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.helpers import _prefetch, inner_kernel, loop_helper

_ROW_STEPS = (-1, 0, 0, 1, -1, -1, 1, 1)
_COL_STEPS = (0, -1, 1, 0, -1, 1, -1, 1)


@njit(cache=True)
def flood_levels(levels, labels, mask, connectivity):
    """Flood ``labels`` (int32, markers > or < 0, 0 elsewhere) over ``mask`` in place.

    ``levels`` are the ranks of the image values (0 = lowest, popped first); the
    neighbours are those of ``skimage.morphology`` connectivity 1 (4) or 2 (8), in
    its order (by distance, then raster offset). Markers outside the mask must be 0.
    Returns 0, or -1 without flooding when ``level | age | pixel`` exceeds 64 bits.
    """
    rows, cols = levels.shape
    n = rows * cols
    flat_levels = levels.ravel()
    flat_labels = labels.ravel()
    flat_mask = mask.ravel()
    top_level = 0
    markers = 0
    for i in range(n):
        if flat_mask[i] and flat_levels[i] > top_level:
            top_level = flat_levels[i]
        if flat_labels[i] != 0:
            markers += 1
    pixel_bits = _bit_length(n - 1)
    age_bits = _bit_length(n + 1)  # ages run from 2 to (pushes + 1) <= n + 1
    if pixel_bits + age_bits + _bit_length(top_level) > 64:
        return -1
    age_shift = np.uint64(pixel_bits)
    level_shift = np.uint64(pixel_bits + age_bits)
    pixel_mask = (np.uint64(1) << age_shift) - np.uint64(1)
    neighbours = 4 if connectivity == 1 else 8
    row_steps = np.array(_ROW_STEPS, np.int64)
    col_steps = np.array(_COL_STEPS, np.int64)
    offsets = row_steps * cols + col_steps

    capacity = max(markers, 1024)
    heap = np.empty(capacity + 2, np.uint64)  # slots 1..items
    items = 0
    for i in range(n):
        if flat_labels[i] == 0:
            continue
        items += 1
        _sift_up(heap, items, (np.uint64(flat_levels[i]) << level_shift) | np.uint64(i), age_shift)
    age = np.uint64(1)
    while items > 0:
        popped = heap[1]
        last = heap[items]
        items -= 1
        if items > 0:
            _sift_down(heap, items, last, age_shift)
        pixel = np.int64(popped & pixel_mask)
        level = popped >> level_shift
        row = pixel // cols
        col = pixel - row * cols
        label = flat_labels[pixel]
        for k in range(neighbours):
            r = row + row_steps[k]
            c = col + col_steps[k]
            if r < 0 or r >= rows or c < 0 or c >= cols:
                continue
            neighbour = pixel + offsets[k]
            if not flat_mask[neighbour] or flat_labels[neighbour] != 0:
                continue
            age += np.uint64(1)
            # Labelled when pushed: no later pop can reach it at a lower cost.
            flat_labels[neighbour] = label
            raised = np.uint64(flat_levels[neighbour])
            if raised < level:
                raised = level
            if items + 2 > len(heap):
                heap = _grown(heap, items)
            items += 1
            _sift_up(heap, items, (raised << level_shift) | (age << age_shift) | np.uint64(neighbour), age_shift)
    return 0


@njit(cache=True)
def clearance_levels(clearance, free):
    """Levels of ``-clearance`` on ``free`` (0 = largest clearance), or a 0 x 0 array.

    A Euclidean distance transform holds square roots of integers: each pixel's
    ``k = round(c^2)`` indexes a table of its value. The levels are exact only if every
    ``k`` has one value and values grow with ``k`` (both checked: else the 0 x 0 array,
    and the caller ranks the values itself); then a level is the number of distinct
    larger values, two passes instead of a sort or a search per pixel.
    """
    rows, cols = clearance.shape
    top = 0.0
    for row in range(rows):
        for col in range(cols):
            if free[row, col] and clearance[row, col] > top:
                top = clearance[row, col]
    failed = np.zeros((0, 0), np.uint32)
    if not top * top < rows * cols + 2.0:  # also NaN; the table stays smaller than the image
        return failed
    size = np.int64(np.rint(np.float64(top) * np.float64(top))) + 1
    values = np.empty(size, np.float32)
    for k in range(size):
        values[k] = -1.0
    for row in range(rows):
        for col in range(cols):
            if free[row, col]:
                value = clearance[row, col]
                if not value >= 0.0:
                    return failed
                k = np.int64(np.rint(np.float64(value) * np.float64(value)))
                if values[k] < 0.0:
                    values[k] = value
                elif values[k] != value:
                    return failed
    rank = np.zeros(size, np.uint32)
    level = -1
    previous = np.float32(np.inf)
    for k in range(size - 1, -1, -1):
        if values[k] < 0.0:
            continue
        if values[k] > previous:
            return failed
        if values[k] < previous:
            level += 1
            previous = values[k]
        rank[k] = level
    levels = np.zeros((rows, cols), np.uint32)
    for row in range(rows):
        for col in range(cols):
            if free[row, col]:
                value = np.float64(clearance[row, col])
                levels[row, col] = rank[np.int64(np.rint(value * value))]
    return levels


@loop_helper
def _bit_length(value):
    bits = 0
    while value > 0:
        bits += 1
        value >>= 1
    return bits


@inner_kernel
def _grown(heap, items):
    grown = np.empty(2 * len(heap), np.uint64)
    for slot in range(items + 1):
        grown[slot] = heap[slot]
    return grown


@loop_helper
def _sift_up(heap, slot, entry, age_shift):
    """Put ``entry`` at ``slot`` and move it up past strictly larger parents (heappush)."""
    key = entry >> age_shift
    while slot > 1:
        parent = slot >> 1
        above = heap[parent]
        if key < (above >> age_shift):
            heap[slot] = above
            slot = parent
        else:
            break
    heap[slot] = entry


@loop_helper
def _sift_down(heap, items, last, age_shift):
    """Refill the root after a pop with ``last`` (heappop's swap and sift-down).

    scikit-image moves the smaller child up (the left one on ties) while it is smaller
    than ``last``; keys only grow along that path, so going to the leaf and climbing back
    past the children that are not smaller than ``last`` gives the same heap.
    """
    key = last >> age_shift
    slot = 1
    while True:
        child = 2 * slot
        if child >= items:
            if child == items:
                heap[slot] = heap[child]
                slot = child
            break
        _prefetch(heap, 8 * slot)  # the great-grandchildren: one cache line
        left = heap[child]
        right = heap[child + 1]
        child += np.int64((right >> age_shift) < (left >> age_shift))
        heap[slot] = heap[child]
        slot = child
    while slot > 1:
        parent = slot >> 1
        above = heap[parent]
        if (above >> age_shift) >= key:
            heap[slot] = above
            slot = parent
        else:
            break
    heap[slot] = last
