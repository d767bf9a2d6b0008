import sys
from common import *
from ursim_core.matching import MatchConfig, M_GRID
ex.PIPELINES.update({"nz-default": (True, "default"), "sketch": (False, "sketch"), "icra": (False, "icra"), "robot": (False, "robot")})
for pl in sys.argv[1:]:
    c = cases(pl)
    print(pl, {n: s.n_regions for n, s in c.sketches.items()}, c.model.n_regions, flush=True)
    for label, cfg in {"T4": MatchConfig(), "T4rd": MatchConfig(disparity="released"), "T3": MatchConfig(variant="T3")}.items():
        t = ex.f1_table(c, cfg, M_GRID)
        show(f"{pl} {label}", t, M_GRID)
