import pickle, sys
import numpy as np
d = pickle.load(open(sys.argv[1], "rb"))
names = sorted(d)
def per_m(n, w, kind):
    D = d[n]; C = D["C"]; tot = D["n1"] + D["n2"] + D["e1"] + D["e2"]
    out = []
    for m, hs in D["rows"]:
        if not hs: out.append(None); continue
        best = None
        for h in hs:
            cs = np.array([C[i, j] for i, j in h["pairs"]])
            if kind == "subs": extra = np.sum(cs > m)
            elif kind == "sumc": extra = cs.sum()
            elif kind == "sumc/m": extra = cs.sum() / max(m, 1e-9)
            score = h["cost"] + w * extra
            if best is None or score < best[0]: best = (score, h)
        out.append((best[0] / tot, best[1], m))
    return out
for kind in ["subs", "sumc"]:
    for w in [0, 0.5, 1, 2, 4]:
        oracle = []; auto = []; fixed = np.zeros(20)
        for n in names:
            rows = per_m(n, w, kind)
            f = [np.mean(r[1]["f1"]) if r else 0 for r in rows]
            oracle.append(max(f)); fixed += np.array(f)
            valid = [r for r in rows if r]
            auto.append(np.mean(min(valid, key=lambda r: (r[0], r[2]))[1]["f1"]))
        print(f"{kind} w={w}: oracle {np.mean(oracle):.3f} bestfixed {fixed.max()/len(names):.3f} at {M[fixed.argmax()] if False else fixed.argmax()} auto-min-norm {np.mean(auto):.3f}")
