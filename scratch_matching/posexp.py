import sys, dataclasses
import numpy as np
from common import *
from ursim_core.matching import *
pl = sys.argv[1] if len(sys.argv) > 1 else "recommended"
c = cases(pl)
def positions(seg, nodes):
    free = seg.labels > 0
    rows, cols = np.nonzero(free)
    r0, r1, c0, c1 = rows.min(), rows.max(), cols.min(), cols.max()
    P = np.array([seg.graph.nodes[n]["centroid"] for n in nodes])
    return np.c_[(P[:, 0] - r0) / (r1 - r0), (P[:, 1] - c0) / (c1 - c0)]
def rank_stats(getC):
    ranks = []
    for n, s in c.sketches.items():
        C, sn, mn = getC(n, s)
        for S, M in c.reference("malcolm", n):
            for a in S:
                for b in M:
                    row = C[sn.index(a)]
                    ranks.append(int(np.sum(row < row[mn.index(b)])))
    return np.mean(ranks), np.mean(np.array(ranks) == 0)
base = {n: prepare(s, c.model, MatchConfig()) for n, s in c.sketches.items()}
def posC(n, s):
    p = base[n]; sn = p.sketch_planar.nodes; mn = p.metric_planar.nodes
    A = positions(s, sn); B = positions(c.model, mn)
    return np.sqrt(((A[:, None] - B[None]) ** 2).sum(-1)), sn, mn
print("signature c", rank_stats(lambda n, s: (base[n].c_matrix, base[n].sketch_planar.nodes, base[n].metric_planar.nodes)))
print("position", rank_stats(posC))
for beta in [0.25, 0.5, 1, 2]:
    print("sig+pos", beta, rank_stats(lambda n, s: (base[n].c_matrix + beta * posC(n, s)[0], posC(n, s)[1], posC(n, s)[2])))
# matching with blended c
for beta in [0, 0.5, 1, 2, 100]:
    table = {a: {} for a in ex.ANNOTATORS}
    for n, s in c.sketches.items():
        p = base[n]
        C = (p.c_matrix + beta * posC(n, s)[0]) / (1 + beta)
        p2 = dataclasses.replace(p, descriptors=dataclasses.replace(p.descriptors, c_matrix=C))
        rs = [match_prepared(p2, m) for m in M_GRID]
        for a in ex.ANNOTATORS:
            table[a][n] = [ex.score_pairs(r.pairs, c.reference(a, n)).f1 for r in rs]
    show(f"blend beta={beta}", table, M_GRID)
