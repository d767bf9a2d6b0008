"""Paper Table 1 analogue: variants x matchers, oracle m (and fixed best), correct scoring."""
from common import *
from ursim_core.matching import MatchConfig, M_GRID
import numpy as np
c = cases("recommended")
for matcher in ("planar", "hungarian", "vf2"):
    for variant in ("baseline", "T1", "T2", "T3", "T4"):
        cfg = MatchConfig.paper(variant=variant, matcher=matcher)
        t = ex.f1_table(c, cfg, M_GRID)
        s = ex.summarise(t)
        orc = [np.array(list(t[a].values())).max(axis=1) for a in ex.ANNOTATORS]
        allv = np.concatenate(orc)
        print(f"{matcher:9s} {variant:8s} oracle median {np.median(allv):.2f} mean {allv.mean():.2f} +- {allv.std():.2f} | best fixed mal {s['malcolm']['best_fixed'][1]:.3f} vas {s['vasiliki']['best_fixed'][1]:.3f}", flush=True)
