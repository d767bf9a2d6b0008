"""Region adjacency graph of a label image, with the region attributes URSIM uses.

The regions are computed by :func:`ursim_core.segmentation.regions.region_table` (no
networkx); this module makes them a ``networkx.Graph``.
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from ursim_core.segmentation.regions import adjacent_pairs, contour_pca_shape, region_table

__all__ = ["region_graph", "adjacent_pairs", "contour_pca_shape"]


def region_graph(labels: np.ndarray) -> nx.Graph:
    """Build the region adjacency graph of a label image (0 = no region).

    One node per region of :func:`~ursim_core.segmentation.regions.region_table`, with its
    attributes ``size``, ``centroid``, ``interior``, ``bbox`` and ``pca_shape``; an edge per pair
    of regions with 4-adjacent pixels, with attribute ``boundary``, the number of such pixel
    pairs. Nodes and edges are inserted in ascending order.

    Examples
    --------
    >>> labels = np.zeros((5, 9), np.int32)
    >>> labels[:, :4] = 1; labels[:, 5:] = 2; labels[2, 4] = 2
    >>> g = region_graph(labels)
    >>> sorted(g.nodes), list(g.edges(data="boundary"))
    ([1, 2], [(1, 2, 1)])
    >>> g.nodes[1]["size"]
    20
    """
    return region_table(labels).to_graph()
