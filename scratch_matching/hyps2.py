"""Dump hypotheses for blended c (signature + beta * position)."""
import pickle, sys, dataclasses
import numpy as np
from common import *
from ursim_core.matching import *
from ursim_core.matching.planar import planar_match
from posexp_lib import positions
pipeline, beta, variant = sys.argv[1], float(sys.argv[2]), sys.argv[3]
c = cases(pipeline)
out = {}
for n, s in c.sketches.items():
    p = prepare(s, c.model, MatchConfig(variant=variant))
    sn, mn = p.sketch_planar.nodes, p.metric_planar.nodes
    A = positions(s, sn); B = positions(c.model, mn)
    P = np.sqrt(((A[:, None] - B[None]) ** 2).sum(-1))
    C = (p.c_matrix + beta * P) / (1 + beta)
    rows = []
    for m in M_GRID:
        seeds = seed_pairs(C, m)
        if not seeds:
            rows.append((m, [])); continue
        r = planar_match(p.sketch_planar, p.metric_planar, (C <= m).tolist(), seeds=seeds, keep_alternatives=True)
        allh = [(float((p.sketch_planar.n_vertices-1)+(p.metric_planar.n_vertices-1)+len(p.sketch_planar.edges)+len(p.metric_planar.edges)), [seeds[0]])] + list(r.alternatives)
        hyps = []
        for cost, pairs in allh:
            rp = [(sn[i], mn[j]) for i, j in pairs]
            f = [ex.score_pairs(rp, c.reference(a, n)).f1 for a in ex.ANNOTATORS]
            hyps.append(dict(cost=cost, pairs=pairs, f1=f, nseeds=len(seeds)))
        rows.append((m, hyps))
    out[n] = dict(rows=rows, n1=len(sn), n2=len(mn), e1=len(p.sketch_planar.edges), e2=len(p.metric_planar.edges), C=C)
pickle.dump(out, open(f"/tmp/hyps_{pipeline}_{variant}_b{beta}.pkl", "wb"))
best_any = [max([np.mean(h["f1"]) for m, hs in d["rows"] for h in hs] or [0]) for d in out.values()]
print("beta", beta, variant, "oracle over all hypotheses:", np.mean(best_any))
