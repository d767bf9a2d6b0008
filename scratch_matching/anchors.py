import sys
import numpy as np
from common import *
from ursim_core.matching import *
pl = sys.argv[1] if len(sys.argv) > 1 else "recommended"
c = cases(pl)
for label, cfg in {"paper": MatchConfig(), "reldisp": MatchConfig(disparity="released"), "model-std": MatchConfig(standardise="model"), "k0.5": MatchConfig(uniqueness_k=0.5), "k1.5": MatchConfig(uniqueness_k=1.5)}.items():
    tot = tp = 0; ranks = []
    for n, s in c.sketches.items():
        p = prepare(s, c.model, cfg)
        ref = c.reference("malcolm", n)
        sc = ex.score_pairs(p.descriptors.anchors, ref)
        tot += len(p.descriptors.anchors); tp += sc.tp
        # GT pairs: rank of c
        C = p.c_matrix; sn = p.sketch_planar.nodes; mn = p.metric_planar.nodes
        for S, M in ref:
            for a in S:
                for b in M:
                    row = C[sn.index(a)]
                    ranks.append(int(np.sum(row < row[mn.index(b)])))
    print(label, "anchors", tot, "tp", tp, "GT-pair rank of c in row: mean", np.mean(ranks), "rank0 frac", np.mean(np.array(ranks) == 0))
