from common import *
from ursim_core.matching import *
c = cases("recommended")
diff = 0
for n, s in c.sketches.items():
    pa = prepare(s, c.model, MatchConfig())
    pb = prepare(s, c.model, MatchConfig(rotation_search="first"))
    for m in M_GRID:
        a = match_prepared(pa, m); b = match_prepared(pb, m)
        if a.pairs != b.pairs: diff += 1
    print(n, s.n_regions, [len(x) for x in pa.sketch_planar.neighbours], [len(x) for x in pa.metric_planar.neighbours], a.cost, a.hypotheses, a.pairs)
print("diff", diff)
