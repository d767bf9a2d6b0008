"""Dump per sketch, per m: all hypotheses with cost, mean c, F1 (both annotators)."""
import pickle, sys
import numpy as np
from common import *
from ursim_core.matching import *
from ursim_core.matching.planar import planar_match
pipeline = sys.argv[1] if len(sys.argv) > 1 else "recommended"
cfgname = sys.argv[2] if len(sys.argv) > 2 else "T4"
cfg = {"T4": MatchConfig(), "T3": MatchConfig(variant="T3"), "T4rd": MatchConfig(disparity="released")}[cfgname]
c = cases(pipeline)
out = {}
for n, s in c.sketches.items():
    p = prepare(s, c.model, cfg)
    C = p.c_matrix
    rows = []
    for m in M_GRID:
        seeds = seed_pairs(C, m)
        if not seeds:
            rows.append((m, [])); continue
        r = planar_match(p.sketch_planar, p.metric_planar, (C <= m).tolist(), seeds=seeds, keep_alternatives=True)
        hyps = []
        single = seeds[0]
        alts = [(r.alternatives[0][0] if False else None)]
        allh = [(float((p.sketch_planar.n_vertices-1)+(p.metric_planar.n_vertices-1)+len(p.sketch_planar.edges)+len(p.metric_planar.edges)), [single])] + list(r.alternatives)
        for cost, pairs in allh:
            rp = [(p.sketch_planar.nodes[i], p.metric_planar.nodes[j]) for i, j in pairs]
            f = [ex.score_pairs(rp, c.reference(a, n)).f1 for a in ex.ANNOTATORS]
            cs = [C[i, j] for i, j in pairs]
            hyps.append(dict(cost=cost, pairs=pairs, meanc=float(np.mean(cs)), maxc=float(np.max(cs)), sumc=float(np.sum(cs)), f1=f, nseeds=len(seeds)))
        rows.append((m, hyps))
    out[n] = dict(rows=rows, n1=p.sketch_planar.n_vertices, n2=p.metric_planar.n_vertices, e1=len(p.sketch_planar.edges), e2=len(p.metric_planar.edges), C=C)
pickle.dump(out, open(f"/tmp/hyps_{pipeline}_{cfgname}.pkl", "wb"))
# upper bounds
best_any = []; best_chosen = []
for n, d in out.items():
    allf = [np.mean(h["f1"]) for m, hs in d["rows"] for h in hs]
    best_any.append(max(allf) if allf else 0)
print("oracle over all hypotheses (mean of annotators):", np.mean(best_any))
