"""Counting a label image's contacts for the steps that track them (ripples, doors).

:func:`start_tracking` compacts the labels and counts every contact with the compiled kernels
(:func:`ursim_core.segmentation.maoris.compiled.kernels`); large images are counted in bands of
rows at the same time, one thread each (the kernels release the GIL), and the bands joined.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ursim_core.cpus import usable_cpus
from ursim_core.segmentation.maoris.compiled import kernels

__all__ = ["start_tracking"]

# Smaller images are counted on one thread: starting threads costs more.
_BAND_PIXELS = 1 << 20


def start_tracking(labels, width, alive, *, bands=None, compacted=None):
    """Compact the labels of a padded, flattened label image in place
    (``_compact_labels``) and count their contacts: ``(original,
    compact_of, state)`` for the compiled steps that track contacts.
    ``compacted``: what ``_compact_labels(labels, alive)`` returned when the caller
    already compacted the labels.

    The state is ``(parent, pixels, following, head, tail, keys, counts,
    meta, slots, total)``: union-find parents of the labels, each zone's
    border candidates linked by ``group_candidates`` (stored contiguously),
    then the counts of ``count_contacts``. Large images are counted in
    ``bands`` of rows at the same time (default: one per CPU, at most 4),
    each on a thread.
    """
    compiled = kernels()
    original, compact_of, n = compiled._compact_labels(labels, alive) if compacted is None else compacted
    if bands is None:
        bands = min(usable_cpus(), 4) if labels.size >= _BAND_PIXELS else 1
    rows = labels.size // width
    edges = [row * width for row in np.linspace(0, rows, bands + 1).astype(int)]
    if bands == 1:
        counted = [compiled.count_contacts(labels, width, n, 0, labels.size)]
    else:
        with ThreadPoolExecutor(bands) as pool:
            counted = list(
                pool.map(lambda k: compiled.count_contacts(labels, width, n, edges[k], edges[k + 1]), range(bands))
            )
    joined = counted[0]
    for band in counted[1:]:
        joined = compiled.join_counts(joined, band)
    pixels, used, keys, counts, meta, slots, total = joined
    pixels, following, head, tail = compiled.group_candidates(labels, pixels, used, n)
    parent = np.arange(n, dtype=np.int32)
    return original, compact_of, (parent, pixels, following, head, tail, keys, counts, meta, slots, total)
