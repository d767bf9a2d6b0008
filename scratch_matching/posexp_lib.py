import numpy as np
def positions(seg, nodes):
    free = seg.labels > 0
    rows, cols = np.nonzero(free)
    r0, r1, c0, c1 = rows.min(), rows.max(), cols.min(), cols.max()
    P = np.array([seg.graph.nodes[n]["centroid"] for n in nodes])
    return np.c_[(P[:, 0] - r0) / (r1 - r0), (P[:, 1] - c0) / (c1 - c0)]
