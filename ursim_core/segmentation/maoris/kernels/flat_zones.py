"""Compiled kernels of MAORIS step 3: flat zones, zone values and sizes, relabelling (numba)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ursim_core.segmentation.maoris.kernels.discs import lookup_bytes
from ursim_core.segmentation.maoris.kernels.helpers import _filled, _grown, _zone_of, inner_kernel


@njit(cache=True)
def label_flat_zones(values, labels):
    """4-connected components of equal non-zero value, numbered 1..N in the
    raster order of their first pixel (0 stays 0), written into ``labels``
    (same shape; any content, every pixel is written) and returned.

    One raster pass with union-find over provisional labels: a set's root is
    always its smallest label, i.e. the one its first pixel created, so
    numbering the roots in order numbers the zones in first-pixel order.
    """
    rows, cols = values.shape
    parent = np.empty(1024, np.int32)
    n = 0
    for row in range(rows):
        for col in range(cols):
            value = values[row, col]
            if value == 0:
                labels[row, col] = 0
                continue
            left = labels[row, col - 1] if col > 0 and values[row, col - 1] == value else 0
            up = labels[row - 1, col] if row > 0 and values[row - 1, col] == value else 0
            if left == 0 and up == 0:
                n += 1
                if n == len(parent):
                    parent = _grown(parent, 2 * n, 0)
                parent[n] = n
                labels[row, col] = n
            else:
                labels[row, col] = left if left != 0 else up
                if left != 0 and up != 0:
                    a, b = _zone_of(left, parent), _zone_of(up, parent)
                    if a < b:
                        parent[b] = a
                    elif b < a:
                        parent[a] = b
    final = np.zeros(n + 1, np.int32)
    zones = 0
    for label in range(1, n + 1):
        root = _zone_of(label, parent)
        if root == label:
            zones += 1
            final[label] = zones
        else:
            final[label] = final[root]
    relabel(labels.ravel(), final)
    return labels


@njit(cache=True)
def zone_values_and_sizes(zones, values, count):
    """Each zone's value (of any of its pixels) and size, zones 0..count - 1."""
    return _values_and_sizes(zones, values, count)


@inner_kernel
def _values_and_sizes(zones, values, count):
    value = np.zeros(count, np.int32)
    size = np.zeros(count, np.int64)
    for row in range(zones.shape[0]):
        for col in range(zones.shape[1]):
            zone = zones[row, col]
            value[zone] = values[row, col]
            size[zone] += 1
    return value, size


@njit(cache=True)
def label_flat_zones_counted(values, labels):
    """:func:`label_flat_zones`, and :func:`zone_values_and_sizes` of its labels (zones 0..N):
    ``(labels, value, size)``. The C kernel (of :func:`label_radii_zones_counted`, which
    segmentations call) counts them in the labelling's own passes."""
    label_flat_zones(values, labels)
    count = np.int64(1)  # typed, not a literal: the helper is compiled for int64 only
    for row in range(labels.shape[0]):
        for col in range(labels.shape[1]):
            count = max(count, np.int64(labels[row, col]) + 1)
    value, size = _values_and_sizes(labels, values, count)
    return labels, value, size


@njit(cache=True)
def label_radii_zones_counted(radii, lo, table):
    """:func:`label_flat_zones_counted` of the value image ``table[radii - lo]``, the labels
    written over ``radii`` (MAORIS steps 2 and 3 at once: the value image, 64 MB of fresh memory
    at 8000 x 8000 px, is never made by the C kernel). IndexError when a radius is outside the
    table."""
    values = np.empty(radii.shape, np.uint8)
    lookup_bytes(radii, lo, table, values)
    return label_flat_zones_counted(values, radii)


@njit(cache=True)
def first_pixels(labels, count):
    """Flat index of the first pixel (raster order) of each label 1..count - 1, -1 if absent."""
    first = _filled(count, -1, np.int64)
    flat = labels.ravel()
    for i in range(len(flat)):
        if first[flat[i]] == -1:
            first[flat[i]] = i
    return first


@njit(cache=True)
def resolve_parents(parent, alive):
    """Follow fusion chains: ``parent[z]`` becomes the live zone z ended in (0 if deleted)."""
    for zone in range(1, len(parent)):
        if alive[zone]:
            parent[zone] = zone
    for zone in range(1, len(parent)):
        root = zone
        while root != 0 and not alive[root]:
            root = parent[root]
        walk = zone
        while walk != root and walk != 0 and not alive[walk]:
            following = parent[walk]
            parent[walk] = root
            walk = following
    parent[0] = 0


@njit(cache=True)
def relabel(labels, lookup):
    """``labels[i] = lookup[labels[i]]`` in place."""
    flat = labels.ravel()
    for i in range(len(flat)):
        flat[i] = lookup[flat[i]]
