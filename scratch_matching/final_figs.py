from common import *
from ursim_core.matching import MatchConfig, M_GRID
import numpy as np
c = cases("recommended")
for label, cfg in {"paper auto": MatchConfig.paper(m="auto"), "default auto": MatchConfig(),
                   "default pos-only (structure score) auto": MatchConfig(hypothesis_score="structure"),
                   "default signature score only (no position) auto": MatchConfig(position_weight=0.0),
                   "default + reflections": MatchConfig(reflections=True)}.items():
    t = ex.f1_table(c, cfg)
    s = ex.summarise(t)
    print(label, " | ".join(f"{a}: mean {s[a]['first'][0]:.3f} median {s[a]['first'][1]:.3f}" for a in ex.ANNOTATORS), "| chosen m:", sorted(set(v[0] for v in t['m'].values())), flush=True)
rc = cases("released")
for legacy in ("fnfix", False, True):
    t = ex.f1_table(rc, MatchConfig.released(), M_GRID, legacy=legacy)
    s = ex.summarise(t)
    print("released pipeline+options legacy", legacy, " | ".join(f"{a}: oracle mean {s[a]['oracle'][0]:.3f} median {s[a]['oracle'][1]:.3f}; best fixed {s[a]['best_fixed'][1]:.3f}@{M_GRID[s[a]['best_fixed'][0]]}" for a in ex.ANNOTATORS))
t = ex.f1_table(rc, MatchConfig(), None)
s = ex.summarise(t)
print("default config on released pipeline, auto:", " | ".join(f"{a}: mean {s[a]['first'][0]:.3f}" for a in ex.ANNOTATORS))
print("released region counts", {n: x.n_regions for n, x in rc.sketches.items()}, "model", rc.model.n_regions)
