import sys
from common import *
from ursim_core.matching import MatchConfig, M_GRID
c = cases("released")
for legacy in ("fnfix", False):
    t = ex.f1_table(c, MatchConfig.released(), M_GRID, legacy=legacy)
    show(f"released options legacy={legacy}", t, M_GRID)
    s = ex.summarise(t)
    print("per-m mean mal", [round(x, 3) for x in s["malcolm"]["per_m_mean"]])
    if legacy == "fnfix":
        for n, v in t["malcolm"].items():
            print(n, " ".join(f"{x:.2f}" for x in v))
