import sys
from common import *
from ursim_core.matching import MatchConfig, M_GRID
pipeline = sys.argv[1] if len(sys.argv) > 1 else "recommended"
c = cases(pipeline)
configs = {
 "paper T4": MatchConfig(),
 "T4 refl": MatchConfig(reflections=True),
 "T4 uniq weights": MatchConfig(weights="uniqueness"),
 "T4 first-rot": MatchConfig(rotation_search="first"),
 "T4 model-std": MatchConfig(standardise="model"),
 "T4 released disp": MatchConfig(disparity="released"),
 "T1": MatchConfig(variant="T1"),
 "T2": MatchConfig(variant="T2"),
 "T3": MatchConfig(variant="T3"),
 "baseline": MatchConfig(variant="baseline"),
 "released all": MatchConfig.released(),
 "T4 hungarian": MatchConfig(matcher="hungarian"),
 "T4 vf2": MatchConfig(matcher="vf2"),
}
only = sys.argv[2:] 
for label, cfg in configs.items():
    if only and label not in only: continue
    t = ex.f1_table(c, cfg, M_GRID)
    show(f"{pipeline} {label}", t, M_GRID)
