import time, sys
from ursim_core.datasets import dataset_root
from ursim_core.matching.experiments import kth_pairs
for p in ("recommended", "released"):
    t = time.perf_counter()
    cases = kth_pairs(dataset_root(), pipeline=p)
    print(p, time.perf_counter() - t, {n: s.n_regions for n, s in cases.sketches.items()}, "model", cases.model.n_regions)
    for a in cases.references:
        print(a, {n: [(sorted(x), sorted(y)) for x, y in r] for n, r in list(cases.references[a].items())[:2]})
