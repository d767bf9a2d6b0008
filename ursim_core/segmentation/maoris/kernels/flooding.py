"""Compiled marker flooding of the clearance watershed: scikit-image's priority flood, exactly.

:func:`flood_levels` pops pixels in the order of ``skimage.segmentation.watershed``
(``_watershed_cy.watershed_raveled`` without compactness or watershed lines, 0.26):
a binary min-heap of (value, age) whose markers enter first, in raster order, with age 0,
and whose every pushed neighbour gets the next age; a pixel takes its label when it is
pushed, from the pixel whose pop pushed it, and its value is raised to that pixel's.
Ages are unique but for the markers, so only the order among markers of one value depends
on the heap's own arrangement: this heap makes the same comparisons and the same moves
as scikit-image's (``heap_general.pxi``), hence pops equal markers in the same order.

Why a heap at all: the pop order of equal markers depends on where the whole history left
them in the heap, and it changes labels (two rooms of the same width meet in the door at
the same time; popping such markers in raster order moves 318 px of the 4000 px building).
Why not a heap to the end: past the last level whose markers carry two labels, popping by
(level, age) in any heap gives the same labels (:func:`_last_tie`), and a FIFO per level
does it without sifting (the largest heaps come last, near the walls).

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

_OUTSIDE = np.int32(-(2**31))
_ROW_STEPS = (-1, 0, 0, 1, -1, -1, 1, 1)
_COL_STEPS = (0, -1, 1, 0, -1, 1, -1, 1)


@njit(cache=True)
def flood_levels(levels, labels, mask, connectivity):
    """Flood ``labels`` (int32, markers > or < 0, 0 elsewhere) over ``mask`` in place.

    ``levels`` are the ranks of the image values (0 = lowest, popped first); the
    neighbours are those of ``skimage.morphology`` connectivity 1 (4) or 2 (8), in
    its order (by distance, then raster offset). Markers outside the mask are dropped,
    and no marker may be -2^31. Returns 0, or -1 without flooding when
    ``level | age | pixel`` exceeds 64 bits or a level the pixel count.
    """
    rows, cols = levels.shape
    n = rows * cols
    flat_levels = levels.ravel()
    flat_labels = labels.ravel()
    flat_mask = mask.ravel()
    # Typed, not literals: numba types a call with what it knows so far, and a literal
    # first compiles the callee for it, in vain.
    top_level = np.int64(0)
    markers = 0
    for i in range(n):
        if flat_mask[i]:
            top_level = max(top_level, flat_levels[i])
            markers += flat_labels[i] != 0
        else:
            flat_labels[i] = _OUTSIDE  # one array to test a neighbour: free and unlabelled is 0
    pixel_bits = _bit_length(n - 1)
    age_bits = _bit_length(n + 1)  # ages run from 2 to (pushes + 1) <= n + 1
    if pixel_bits + age_bits + _bit_length(top_level) > 64 or top_level > n:  # levels are ranks
        _restore_outside(flat_labels)
        return -1
    shifts = (np.uint64(pixel_bits), np.uint64(pixel_bits + age_bits))
    heap = np.empty(max(markers, 1024) + 2, np.uint64)  # slots 1..items
    items = np.int64(0)
    for i in range(n):
        if flat_labels[i] != 0 and flat_labels[i] != _OUTSIDE:
            items += 1
            _sift_up(heap, items, (np.uint64(flat_levels[i]) << shifts[1]) | np.uint64(i), shifts[0])
    state = _heap_flood(
        flat_levels,
        flat_labels,
        levels.shape,
        connectivity,
        heap,
        items,
        shifts,
        _last_tie(flat_levels, flat_labels, top_level),
    )
    _bucket_flood(flat_levels, flat_labels, levels.shape, connectivity, state[0], state[1], state[2], shifts, top_level)
    _restore_outside(flat_labels)
    return 0


@inner_kernel
def _last_tie(flat_levels, flat_labels, top_level):
    """The highest level whose markers carry two labels or more (-1 if none).

    The heap's own order matters only there: markers of one level pop in one run, and
    permuting a run of pops of one label permutes the ages of what they push among
    themselves only, which changes no label (each later run of one label labels the
    same pixels whatever its order). Past this level a FIFO per level pops alike.
    """
    first = np.empty(top_level + 1, np.int32)
    for level in range(top_level + 1):
        first[level] = 0
    last = -1
    for i in range(len(flat_labels)):
        label = flat_labels[i]
        if label == 0 or label == _OUTSIDE:
            continue
        level = np.int64(flat_levels[i])
        if first[level] == 0:
            first[level] = label
        elif first[level] != label and level > last:
            last = level
    return last


@inner_kernel
def _heap_flood(flat_levels, flat_labels, shape, connectivity, heap, items, shifts, last_tie):
    """scikit-image's pops while a level of tied markers of two labels remains."""
    rows, cols = shape
    age_shift, level_shift = shifts
    pixel_mask = (np.uint64(1) << age_shift) - np.uint64(1)
    steps = _steps(cols, connectivity)
    age = np.uint64(1)
    while items > 0:
        popped = heap[1]
        level = popped >> level_shift
        if np.int64(level) > last_tie:
            break
        last = heap[items]
        items -= 1
        if items > 0:
            _sift_down(heap, items, last, age_shift)
        pixel = np.int64(popped & pixel_mask)
        row = pixel // cols
        col = pixel - row * cols
        label = flat_labels[pixel]
        for k in range(len(steps)):
            r = row + steps[k, 0]
            c = col + steps[k, 1]
            if r < 0 or r >= rows or c < 0 or c >= cols:
                continue
            neighbour = pixel + steps[k, 2]
            if flat_labels[neighbour] != 0:
                continue
            age += np.uint64(1)
            # Labelled when pushed: no later pop can reach it at a lower cost.
            flat_labels[neighbour] = label
            raised = max(np.uint64(flat_levels[neighbour]), level)
            if items + 2 > len(heap):
                heap = _grown(heap, items)
            items += 1
            _sift_up(heap, items, (raised << level_shift) | (age << age_shift) | np.uint64(neighbour), age_shift)
    return heap, items, age


@inner_kernel
def _bucket_flood(flat_levels, flat_labels, shape, connectivity, heap, items, age, shifts, top_level):
    """The rest of the pops, in (level, age) order: the heap's entries sorted, then per
    level those entries before the pixels pushed since (they are younger)."""
    rows, cols = shape
    age_shift, level_shift = shifts
    pixel_mask = (np.uint64(1) << age_shift) - np.uint64(1)
    steps = _steps(cols, connectivity)
    # Sorted with their pixel bits: equal markers (of one label, see _last_tie) in raster order.
    waiting = np.sort(heap[1 : items + 1])
    following = np.empty(len(flat_labels), np.int32)
    head = np.empty(top_level + 1, np.int64)
    tail = np.empty(top_level + 1, np.int64)
    for level in range(top_level + 1):
        head[level] = -1
        tail[level] = -1
    next_waiting = 0
    for level in range(top_level + 1):
        while True:
            if next_waiting < len(waiting) and np.int64(waiting[next_waiting] >> level_shift) == level:
                pixel = np.int64(waiting[next_waiting] & pixel_mask)
                next_waiting += 1
            elif head[level] >= 0:
                pixel = head[level]
                head[level] = following[pixel]
            else:
                break
            row = pixel // cols
            col = pixel - row * cols
            label = flat_labels[pixel]
            for k in range(len(steps)):
                r = row + steps[k, 0]
                c = col + steps[k, 1]
                if r < 0 or r >= rows or c < 0 or c >= cols:
                    continue
                neighbour = pixel + steps[k, 2]
                if flat_labels[neighbour] != 0:
                    continue
                flat_labels[neighbour] = label
                raised = max(np.int64(flat_levels[neighbour]), level)
                following[neighbour] = -1
                if head[raised] < 0:
                    head[raised] = neighbour
                else:
                    following[tail[raised]] = neighbour
                tail[raised] = neighbour


@inner_kernel
def _steps(cols, connectivity):
    """(row step, col step, flat step) of each neighbour, in scikit-image's order."""
    count = 4 if connectivity == 1 else 8
    steps = np.empty((count, 3), np.int64)
    for k in range(count):
        steps[k, 0] = _ROW_STEPS[k]
        steps[k, 1] = _COL_STEPS[k]
        steps[k, 2] = _ROW_STEPS[k] * cols + _COL_STEPS[k]
    return steps


@loop_helper
def _restore_outside(flat_labels):
    for i in range(len(flat_labels)):
        if flat_labels[i] == _OUTSIDE:
            flat_labels[i] = 0


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
