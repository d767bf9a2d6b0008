import numpy as np
from common import *
from ursim_core.matching import *
from ursim_core import descriptors as D
from posexp_lib import positions
c = cases("recommended")
for wpos in [0, 0.5, 1, 2, 4]:
  for k in [1.0]:
    tot = tp = 0
    for n, s in c.sketches.items():
        sn, sv = D.region_attributes(s.graph); mn, mv = D.region_attributes(c.model.graph)
        zs, zm = D.standardise(sv), D.standardise(mv)
        us, um = D.unique_mask(zs, k=k), D.unique_mask(zm, k=k)
        ps, pm = positions(s, sn), positions(c.model, mn)
        rs, rm = np.flatnonzero(us), np.flatnonzero(um)
        cost = D.disparity_matrix(zs[rs], zm[rm]) + wpos * np.sqrt(((ps[rs][:, None] - pm[rm][None]) ** 2).sum(-1))
        pairs = [(sn[rs[i]], mn[rm[j]]) for i, j in D.anchor_pairs(cost)]
        sc = ex.score_pairs(pairs, c.reference("malcolm", n))
        tot += len(pairs); tp += sc.tp
    print("wpos", wpos, "k", k, "anchors", tot, "tp", tp)
