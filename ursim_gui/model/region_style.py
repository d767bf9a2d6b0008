"""Qt-free rendering of label images: colour lookup tables, outlines, label positions.

Everything here works on numpy arrays so it can be tested without Qt and stays fast on
big maps: the region overlay is one lookup-table indexing ``lut[labels]`` (no per-region
polygons), outlines are two vectorised neighbour comparisons, and masks for hover and
selection are computed on a region's bounding box only.

Colours are ``(r, g, b)`` tuples of ints 0..255; RGBA images are ``uint8`` arrays of
shape ``(rows, cols, 4)``.
"""

from __future__ import annotations

import colorsys
from collections.abc import Iterable, Mapping

import numpy as np

from ursim_core.segmentation.regions import row_bands

__all__ = [
    "Colour",
    "NEUTRAL_REGION",
    "palette_colour",
    "clique_colour",
    "region_colour_table",
    "overlay_rgba",
    "outline_mask",
    "region_label_positions",
    "region_mask",
]

Colour = tuple[int, int, int]

#: Colour of regions that are part of no clique once correspondences exist.
NEUTRAL_REGION: Colour = (176, 180, 188)

_GOLDEN_RATIO_CONJUGATE = 0.618033988749895


def palette_colour(index: int) -> Colour:
    """A well separated, saturated colour for ``index`` (deterministic).

    Hues step by the golden ratio so consecutive indices never look alike; saturation
    and value alternate over three levels so hues that come back around stay distinct.

    Examples
    --------
    >>> palette_colour(0) != palette_colour(1)
    True
    """
    hue = (0.08 + index * _GOLDEN_RATIO_CONJUGATE) % 1.0
    saturation = (0.75, 0.55, 0.9)[index % 3]
    value = (0.95, 0.8, 0.7)[(index // 3) % 3]
    r, g, b = colorsys.hsv_to_rgb(hue, saturation, value)
    return int(round(r * 255)), int(round(g * 255)), int(round(b * 255))


def clique_colour(clique_id: int) -> Colour:
    """The colour of a clique, the same in both views and in the figure legend."""
    return palette_colour(int(clique_id))


def region_colour_table(
    max_label: int,
    colours: Mapping[int, Colour] | None = None,
    *,
    default: Colour | None = None,
    alpha: int = 255,
) -> np.ndarray:
    """Colour lookup table indexed by region id.

    Parameters
    ----------
    max_label : int
        Largest region id; the table has ``max_label + 1`` rows.
    colours : mapping of region id to colour, optional
        Explicit colours (clique colours). Ids outside ``1..max_label`` are ignored.
    default : colour, optional
        Colour of regions not in ``colours``; ``None`` gives each region its own
        palette colour (plain segmentation display).
    alpha : int
        Opacity 0..255 of every region. Label 0 (no region) is always transparent.

    Returns
    -------
    ndarray of uint8, shape (max_label + 1, 4)
    """
    n = int(max_label) + 1
    table = np.zeros((n, 4), np.uint8)
    if n > 1:
        if default is None:
            table[1:, :3] = [palette_colour(i) for i in range(1, n)]
        else:
            table[1:, :3] = default
        table[1:, 3] = alpha
    for region, colour in (colours or {}).items():
        if 1 <= int(region) < n:
            table[int(region), :3] = colour
    return table


def overlay_rgba(labels: np.ndarray, table: np.ndarray) -> np.ndarray:
    """RGBA overlay of a label image: ``table[labels]``, contiguous.

    Labels above the table's range are shown transparent rather than raising, so a stale
    table never crashes the view.
    """
    labels = np.asarray(labels)
    if labels.size and int(labels.max()) >= len(table):
        table = np.vstack([table, np.zeros((int(labels.max()) + 1 - len(table), 4), np.uint8)])
    return np.ascontiguousarray(table[labels])


def outline_mask(labels: np.ndarray) -> np.ndarray:
    """Pixels on the border of a region (a 4-neighbour with another label), as bool.

    Both pixels of each differing pair are marked, but only where they belong to a
    region, so walls (label 0) stay clean.
    """
    labels = np.asarray(labels)
    edge = np.empty(labels.shape, bool)
    # In bands of rows, each with one row of context above and below: full-size masks were
    # several images of fresh memory for a building-sized map (0.5 s a call at 8000 x 8000 px).
    total = labels.shape[0]
    for rows in row_bands(labels):
        start, stop = rows.start, rows.stop
        low, high = max(0, start - 1), min(total, stop + 1)
        block = labels[low:high]
        marked = np.zeros(block.shape, bool)
        vertical = block[1:, :] != block[:-1, :]
        horizontal = block[:, 1:] != block[:, :-1]
        marked[1:, :] |= vertical
        marked[:-1, :] |= vertical
        marked[:, 1:] |= horizontal
        marked[:, :-1] |= horizontal
        marked &= block > 0
        edge[start:stop] = marked[start - low : stop - low]
    return edge


def region_label_positions(graph) -> dict[int, tuple[float, float]]:
    """Where to print each region id: its interior point (row, col), else its centroid.

    ``graph`` is a region graph of :func:`ursim_core.segmentation.graph.region_graph`; the interior
    point is the distance-transform maximum, so the text sits inside even concave rooms.
    """
    positions: dict[int, tuple[float, float]] = {}
    for region, attrs in graph.nodes(data=True):
        point = attrs.get("interior") or attrs.get("centroid")
        if point is not None:
            positions[int(region)] = (float(point[0]), float(point[1]))
    return positions


def region_mask(
    labels: np.ndarray, region: int, bbox: Iterable[int] | None = None
) -> tuple[np.ndarray, tuple[int, int]]:
    """Boolean mask of one region cropped to its bounding box, and the box's (row, col).

    Parameters
    ----------
    labels : ndarray of int
        The label image.
    region : int
        Region id.
    bbox : (min_row, min_col, max_row, max_col), optional
        The region's box (max exclusive), from the graph; computed when missing.
    """
    if bbox is None:
        rows, cols = np.nonzero(labels == region)
        if rows.size == 0:
            return np.zeros((0, 0), bool), (0, 0)
        bbox = (rows.min(), cols.min(), rows.max() + 1, cols.max() + 1)
    r0, c0, r1, c1 = (int(v) for v in bbox)
    return labels[r0:r1, c0:c1] == region, (r0, c0)
