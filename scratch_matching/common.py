import pickle, os, sys, time
from pathlib import Path
from ursim_core.datasets import dataset_root
from ursim_core.matching import experiments as ex

CACHE = Path("/tmp/ursim_matching_cache")
CACHE.mkdir(exist_ok=True)

def cases(pipeline="recommended", tag=""):
    path = CACHE / f"{pipeline}{tag}.pkl"
    if path.exists():
        return pickle.loads(path.read_bytes())
    c = ex.kth_pairs(dataset_root(), pipeline=pipeline)
    path.write_bytes(pickle.dumps(c))
    return c

def show(label, table, m_values=None):
    s = ex.summarise(table)
    parts = [label]
    for a in ("malcolm", "vasiliki"):
        bi, bmean, bmed = s[a]["best_fixed"]
        om, omed = s[a]["oracle"]
        bm = m_values[bi] if m_values else None
        parts.append(f"{a[:3]}: oracle {om:.3f}/{omed:.3f} bestfix m={bm} {bmean:.3f}/{bmed:.3f}")
    parts.append(f"both oracle {s['both']['oracle']:.3f} bestfix {s['both']['best_fixed']:.3f}")
    print(" | ".join(parts), flush=True)
    return s
