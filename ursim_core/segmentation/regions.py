"""The regions of a label image and their attributes, without networkx.

:func:`region_table` computes what URSIM needs of each region (size, centroid, interior
point, bounding box, contour shape) and the boundary between each pair of touching regions,
as a :class:`RegionTable` of plain dicts. :func:`ursim_core.segmentation.graph.region_graph`
makes the same as a ``networkx.Graph``; a command that only writes a segmentation
(``ursim segment``) never imports networkx (about a tenth of a second of its start).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.segmentation.canonical import free_window

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["RegionTable", "region_table", "adjacent_pairs", "contour_pca_shape", "row_bands"]


@dataclass(frozen=True)
class RegionTable:
    """The regions of a label image: what :func:`~ursim_core.segmentation.graph.region_graph`
    puts in its graph, as plain dicts.

    ``nodes`` and ``edges`` read as a ``networkx.Graph``'s do (``table.nodes[3]["interior"]``,
    ``for a, b in table.edges``, ``3 in table``), so that code drawing or writing regions takes
    either.

    Attributes
    ----------
    nodes : dict
        Region id -> ``{"size", "centroid", "interior", "bbox", "pca_shape"}``, ids ascending.
    edges : dict
        ``(a, b)`` with ``a < b`` -> ``boundary``, the number of 4-adjacent pixel pairs.
    contacts : dict
        ``(a, b)`` as in ``edges`` -> ``contact``, the mean (row, col) of the midpoints of those
        pixel pairs: where the two regions touch (a door, for two rooms split at it).

    Examples
    --------
    >>> labels = np.array([[1, 1, 2, 2], [1, 1, 2, 2], [3, 3, 3, 3]])
    >>> table = region_table(labels)
    >>> len(table), 3 in table, table.nodes[1]["centroid"], table.edges[1, 3]
    (3, True, (0.5, 0.5), 2)
    >>> table.neighbours()[3], table.contacts[1, 2]  # regions 1 and 2 touch between columns 1 and 2
    ([1, 2], (0.5, 1.5))
    >>> RegionTable.from_graph(table.to_graph()) == table
    True
    """

    nodes: dict[int, dict]
    edges: dict[tuple[int, int], int]
    contacts: dict[tuple[int, int], tuple[float, float]] = dataclasses.field(default_factory=dict)

    def __contains__(self, region: object) -> bool:
        return region in self.nodes

    def __len__(self) -> int:
        return len(self.nodes)

    def number_of_nodes(self) -> int:
        return len(self.nodes)

    def number_of_edges(self) -> int:
        return len(self.edges)

    def neighbours(self) -> dict[int, list[int]]:
        """Each region's neighbours, ascending."""
        around: dict[int, list[int]] = {region: [] for region in self.nodes}
        for a, b in self.edges:
            around[a].append(b)
            around[b].append(a)
        return {region: sorted(others) for region, others in around.items()}

    def to_graph(self) -> nx.Graph:
        """The table as the ``networkx.Graph`` of :func:`~ursim_core.segmentation.graph.region_graph`
        (nodes, then edges, in the table's order)."""
        import networkx as nx

        graph = nx.Graph()
        graph.add_nodes_from((region, dict(data)) for region, data in self.nodes.items())
        graph.add_edges_from((a, b, {"boundary": count}) for (a, b), count in self.edges.items())
        for (a, b), contact in self.contacts.items():
            graph.edges[a, b]["contact"] = contact
        return graph

    @classmethod
    def from_graph(cls, graph: nx.Graph) -> RegionTable:
        """The table of a region graph (given in place of a label image's)."""
        edges, contacts = {}, {}
        for a, b, data in graph.edges(data=True):
            edges[min(a, b), max(a, b)] = data.get("boundary", 0)
            if "contact" in data:
                contacts[min(a, b), max(a, b)] = data["contact"]
        return cls(
            nodes={region: dict(data) for region, data in graph.nodes(data=True)}, edges=edges, contacts=contacts
        )


def adjacent_pairs(labels: np.ndarray) -> dict[tuple[int, int], int]:
    """Count 4-adjacent pixel pairs between different non-zero labels.

    Parameters
    ----------
    labels : ndarray of int, shape (rows, cols)
        Label image, 0 = no region.

    Returns
    -------
    dict
        ``{(a, b): n}`` with ``a < b`` and ``n`` the number of 4-adjacent pixel pairs.

    Examples
    --------
    >>> labels = np.array([[1, 1, 2], [1, 0, 2]])
    >>> adjacent_pairs(labels)
    {(1, 2): 1}
    """
    return _adjacency(labels)[0]


def _adjacency(labels: np.ndarray) -> tuple[dict, dict]:
    """:func:`adjacent_pairs`' counts, and the mean (row, col) of each pair's pixel-pair midpoints
    (``RegionTable.contacts``)."""
    labels = np.asarray(labels)
    firsts, seconds, rows_at, cols_at = [], [], [], []
    # In bands of rows (each with the next band's first row, for the pairs across): the masks
    # of a band stay small, where full-size ones were several images of fresh memory (64 MB
    # each at 8000 x 8000 px). The pairs are counted, so their order does not matter.
    for rows in row_bands(labels):
        band = labels[rows.start : rows.stop + 1]
        height = rows.stop - rows.start
        # Side by side (the midpoint half a column right), then one above the other (half a row down).
        for (a, b), (down, right) in (
            ((band[:height, :-1], band[:height, 1:]), (0.0, 0.5)),
            ((band[:-1, :], band[1:, :]), (0.5, 0.0)),
        ):
            touching = a != b
            touching &= a != 0
            touching &= b != 0
            firsts.append(a[touching])
            seconds.append(b[touching])
            found_rows, found_cols = np.divmod(np.flatnonzero(touching), touching.shape[1])
            rows_at.append(found_rows + (rows.start + down))
            cols_at.append(found_cols + right)
    if not firsts:
        return {}, {}
    first = np.concatenate(firsts).astype(np.int64)
    second = np.concatenate(seconds).astype(np.int64)
    low, high = np.minimum(first, second), np.maximum(first, second)
    if low.size == 0:
        return {}, {}
    base = int(high.max()) + 1
    keys, inverse, counts = np.unique(low * base + high, return_inverse=True, return_counts=True)
    row_means = np.bincount(inverse, weights=np.concatenate(rows_at)) / counts
    col_means = np.bincount(inverse, weights=np.concatenate(cols_at)) / counts
    pairs = [(int(k // base), int(k % base)) for k in keys.tolist()]
    edges = {pair: int(n) for pair, n in zip(pairs, counts.tolist())}
    contacts = {pair: (float(r), float(c)) for pair, r, c in zip(pairs, row_means.tolist(), col_means.tolist())}
    return edges, contacts


#: Pixels per band of :func:`row_bands`: the masks of a band then fit a core's 2 MB cache
#: (:func:`adjacent_pairs` at 8000 px: 0.07-0.14 s, against 0.16-0.19 s for bands of 1024 rows
#: and 0.17-0.79 s for the whole image).
BAND_PIXELS = 1 << 18


def row_bands(image: np.ndarray, *, pixels: int = BAND_PIXELS) -> Iterator[slice]:
    """Consecutive bands of rows of ``image``, about ``pixels`` pixels each (at least one row).

    For passes over a whole label image whose temporaries (masks, index copies) would otherwise
    be image-sized fresh memory: 64-512 MB each at 8000 x 8000 px.

    Examples
    --------
    >>> [(band.start, band.stop) for band in row_bands(np.zeros((5, 4)), pixels=8)]
    [(0, 2), (2, 4), (4, 5)]
    """
    rows = image.shape[0]
    step = max(1, pixels // max(1, image.shape[1]))
    for start in range(0, rows, step):
        yield slice(start, min(rows, start + step))


def contour_pca_shape(mask: np.ndarray) -> float:
    """Shape attribute of a region: ``1 - lambda_min / lambda_max`` of its contour points.

    As the released URSIM code (original_code.md §1.2), PCA runs on the points of the
    region's longest contour (``RETR_LIST``, ``CHAIN_APPROX_NONE``), not on its pixels.
    0 means round or square, values near 1 elongated; degenerate regions give 0.

    Examples
    --------
    >>> square = np.zeros((12, 12), bool); square[1:11, 1:11] = True
    >>> round(contour_pca_shape(square), 3)
    0.0
    >>> bar = np.zeros((8, 42), bool); bar[2:6, 1:41] = True
    >>> contour_pca_shape(bar) > 0.9
    True
    """
    return _pca_shape_of_padded(np.pad(np.asarray(mask, dtype=np.uint8), 1))


def _pca_shape_of_padded(padded: np.ndarray) -> float:
    """:func:`contour_pca_shape` of a uint8 mask already padded by one zero pixel (findContours
    does not write to it: OpenCV 3.2 and later)."""
    contours, _ = cv2.findContours(padded, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
    if not contours:
        return 0.0
    points = max(contours, key=len).reshape(-1, 2).astype(np.float64)
    if len(points) < 3:
        return 0.0
    eigenvalues = np.linalg.eigvalsh(np.cov(points, rowvar=False))
    largest = float(eigenvalues[-1])
    if largest <= 0.0:
        return 0.0
    return float(np.clip(1.0 - max(float(eigenvalues[0]), 0.0) / largest, 0.0, 1.0))


def _runs(labels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Runs of equal non-zero labels along the rows: ``(label, row, col_start, col_stop)``."""
    # Found in the box of the non-zero labels (the same runs: 0 lies on every side of it): a
    # sketch turned by 30 degrees has 3.6 million pixels for 0.3 million labelled, and the
    # passes below took 10 ms of its region table's 24 against 3 in the box.
    box = free_window(labels)
    if box is not None and labels[box].shape != labels.shape:
        run_labels, run_rows, run_cols, stops = _runs(labels[box])
        return run_labels, run_rows + box[0].start, run_cols + box[1].start, stops + box[1].start
    cols = labels.shape[1]
    # In bands of rows, as adjacent_pairs: a full-size mask was 64 MB of fresh memory at 8000 px.
    found_rows, found_cols = [np.zeros(0, np.intp)], [np.zeros(0, np.intp)]
    for rows in row_bands(labels):
        band = labels[rows]
        starts = np.ones(band.shape, bool)
        np.not_equal(band[:, 1:], band[:, :-1], out=starts[:, 1:])
        band_rows, band_cols = np.nonzero(starts)
        band_rows += rows.start
        found_rows.append(band_rows)
        found_cols.append(band_cols)
    run_rows, run_cols = np.concatenate(found_rows), np.concatenate(found_cols)
    run_labels = labels[run_rows, run_cols]
    # A run stops where the next one starts on the same row, else at the row's end.
    stops = np.full(len(run_cols), cols, np.intp)
    same_row = run_rows[1:] == run_rows[:-1]
    stops[:-1][same_row] = run_cols[1:][same_row]
    keep = run_labels > 0
    return run_labels[keep], run_rows[keep], run_cols[keep], stops[keep]


def _bounding_boxes(labels: np.ndarray, count: int, runs=None) -> np.ndarray:
    """``(row_start, col_start, row_stop, col_stop)`` of each label 0..count - 1 (stops
    exclusive; as ``scipy.ndimage.find_objects``, without importing scipy.ndimage).

    Computed on the runs of equal labels along rows, far fewer than the pixels.
    """
    rows, cols = labels.shape
    run_labels, run_rows, run_cols, stops = _runs(labels) if runs is None else runs
    boxes = np.empty((count, 4), np.intp)
    boxes[:, 0], boxes[:, 1], boxes[:, 2], boxes[:, 3] = rows, cols, 0, 0
    np.minimum.at(boxes[:, 0], run_labels, run_rows)
    np.minimum.at(boxes[:, 1], run_labels, run_cols)
    np.maximum.at(boxes[:, 2], run_labels, run_rows + 1)
    np.maximum.at(boxes[:, 3], run_labels, stops)
    return boxes


def _coordinate_sums(runs, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Sums of the row and of the column indices of each label's pixels, from its runs.

    Integer sums (exact in float64 below 2**53), so the centroids are those of a sum over the
    pixels, without two int64 index images of the map's size.
    """
    run_labels, run_rows, run_cols, stops = runs
    lengths = (stops - run_cols).astype(np.int64)
    row_sums = np.bincount(run_labels, weights=run_rows.astype(np.int64) * lengths, minlength=count)
    # Columns start..stop-1 sum to (start + stop - 1) * length / 2, an integer.
    col_sums = np.bincount(run_labels, weights=(run_cols + stops - 1).astype(np.int64) * lengths // 2, minlength=count)
    return row_sums, col_sums


def region_table(labels: np.ndarray) -> RegionTable:
    """The regions of a label image and their attributes (no networkx).

    Parameters
    ----------
    labels : ndarray of int, shape (rows, cols)
        0 = no region, regions are positive integers.

    Returns
    -------
    RegionTable
        Per region id: ``size`` (pixels), ``centroid`` (row, col), ``interior`` (row, col: the
        pixel farthest from the region's border, a point safely inside even for non-convex
        regions), ``bbox`` (min_row, min_col, max_row, max_col; max exclusive) and
        ``pca_shape`` (see :func:`contour_pca_shape`); per pair of regions with 4-adjacent
        pixels, the number of such pixel pairs (``edges``) and where they touch (``contacts``).

    Examples
    --------
    >>> labels = np.zeros((5, 9), np.int32)
    >>> labels[:, :4] = 1; labels[:, 5:] = 2; labels[2, 4] = 2
    >>> table = region_table(labels)
    >>> sorted(table.nodes), table.edges, table.nodes[1]["size"]
    ([1, 2], {(1, 2): 1}, 20)
    """
    labels = np.asarray(labels)
    nodes: dict[int, dict] = {}
    if labels.size == 0 or not labels.any():
        return RegionTable(nodes=nodes, edges={})
    if labels.dtype.kind == "i" and int(labels.min()) < 0:
        # The runs keep positive labels only: a negative one would be dropped without a word.
        raise ParameterError("label image has negative labels (0 = no region, regions 1, 2, ...)", field="labels")
    n_max = int(labels.max())
    runs = _runs(labels)
    # From the runs, not the pixels: a bincount of the image converts it to int64 first (512 MB
    # of fresh memory at 8000 x 8000 px, 0.24-1.9 s measured, against about a millisecond).
    run_labels, _, run_cols, stops = runs
    sizes = np.bincount(run_labels, weights=stops - run_cols, minlength=n_max + 1).astype(np.int64)
    row_sums, col_sums = _coordinate_sums(runs, n_max + 1)
    boxes = _bounding_boxes(labels, n_max + 1, runs)
    del runs
    # Per region: its mask padded by one zero pixel, made once for the distance transform and
    # the contour (a region's own border, image edges included, is then the transform's zero).
    # The argmax runs over the padded transform itself: its zero border never holds the maximum
    # (every region pixel is at least 1 from it) and its raster order is the crop's, so the
    # first maximum is the same pixel as the crop's, without a copy of the crop.
    for index in np.flatnonzero(sizes[1:]).tolist():
        index += 1
        row_start, col_start, row_stop, col_stop = boxes[index].tolist()
        padded = np.zeros((row_stop - row_start + 2, col_stop - col_start + 2), np.uint8)
        np.equal(labels[row_start:row_stop, col_start:col_stop], index, out=padded[1:-1, 1:-1].view(bool))
        inside = cv2.distanceTransform(padded, cv2.DIST_L2, 5)
        peak_row, peak_col = divmod(int(inside.argmax()), inside.shape[1])
        size = int(sizes[index])
        nodes[index] = {
            "size": size,
            "centroid": (float(row_sums[index] / size), float(col_sums[index] / size)),
            "interior": (row_start + peak_row - 1, col_start + peak_col - 1),
            "bbox": (row_start, col_start, row_stop, col_stop),
            "pca_shape": _pca_shape_of_padded(padded),
        }
    edges, contacts = _adjacency(labels)
    return RegionTable(nodes=nodes, edges=edges, contacts=contacts)
