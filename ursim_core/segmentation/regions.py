"""The regions of a label image and their attributes, without networkx.

:func:`region_table` computes what URSIM needs of each region (size, centroid, interior
point, bounding box, contour shape) and the boundary between each pair of touching regions,
as a :class:`RegionTable` of plain dicts. :func:`ursim_core.segmentation.graph.region_graph`
makes the same as a ``networkx.Graph``; a command that only writes a segmentation
(``ursim segment``) never imports networkx (about a tenth of a second of its start).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["RegionTable", "region_table", "adjacent_pairs", "contour_pca_shape"]


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
    """

    nodes: dict[int, dict]
    edges: dict[tuple[int, int], int]

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
        return graph

    @classmethod
    def from_graph(cls, graph: nx.Graph) -> RegionTable:
        """The table of a region graph (given in place of a label image's)."""
        edges = {(min(a, b), max(a, b)): data.get("boundary", 0) for a, b, data in graph.edges(data=True)}
        return cls(nodes={region: dict(data) for region, data in graph.nodes(data=True)}, edges=edges)


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
    labels = np.asarray(labels)
    firsts, seconds = [], []
    for a, b in ((labels[:, :-1], labels[:, 1:]), (labels[:-1, :], labels[1:, :])):
        touching = (a != b) & (a != 0) & (b != 0)
        firsts.append(a[touching])
        seconds.append(b[touching])
    first = np.concatenate(firsts).astype(np.int64)
    second = np.concatenate(seconds).astype(np.int64)
    low, high = np.minimum(first, second), np.maximum(first, second)
    if low.size == 0:
        return {}
    base = int(high.max()) + 1
    keys, counts = np.unique(low * base + high, return_counts=True)
    return {(int(k // base), int(k % base)): int(n) for k, n in zip(keys, counts)}


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
    padded = np.pad(np.asarray(mask, dtype=np.uint8), 1)
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
    cols = labels.shape[1]
    starts = np.ones(labels.shape, bool)
    starts[:, 1:] = labels[:, 1:] != labels[:, :-1]
    run_rows, run_cols = np.nonzero(starts)
    del starts
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
        pixels, the number of such pixel pairs.

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
    n_max = int(labels.max())
    flat = labels.ravel()
    sizes = np.bincount(flat, minlength=n_max + 1)
    runs = _runs(labels)
    row_sums, col_sums = _coordinate_sums(runs, n_max + 1)
    boxes = _bounding_boxes(labels, n_max + 1, runs)
    del runs
    for index in range(1, n_max + 1):
        if sizes[index] == 0:
            continue
        box = (slice(int(boxes[index, 0]), int(boxes[index, 2])), slice(int(boxes[index, 1]), int(boxes[index, 3])))
        mask = labels[box] == index
        # Distance to the region's own border (zero padding makes image edges borders too).
        inside = cv2.distanceTransform(np.pad(mask.astype(np.uint8), 1), cv2.DIST_L2, 5)[1:-1, 1:-1]
        peak_row, peak_col = np.unravel_index(int(np.argmax(inside)), inside.shape)
        nodes[index] = {
            "size": int(sizes[index]),
            "centroid": (float(row_sums[index] / sizes[index]), float(col_sums[index] / sizes[index])),
            "interior": (int(box[0].start + peak_row), int(box[1].start + peak_col)),
            "bbox": (box[0].start, box[1].start, box[0].stop, box[1].stop),
            "pca_shape": contour_pca_shape(mask),
        }
    return RegionTable(nodes=nodes, edges=adjacent_pairs(labels))
