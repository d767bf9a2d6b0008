import pickle, sys, itertools
import numpy as np
d = pickle.load(open(sys.argv[1], "rb"))
names = sorted(d)
def chosen(hs):
    # planar choice: min cost, earliest
    best = None
    for h in hs:
        if best is None or h["cost"] < best["cost"]: best = h
    return best
# per m chosen
table = {}
for n in names:
    table[n] = [(m, chosen(hs)) for m, hs in d[n]["rows"]]
def evaluate(rule):
    f = []
    for n in names:
        h = rule(n)
        f.append(np.mean(h["f1"]) if h else 0.0)
    return np.mean(f), np.median(f)
tot = lambda n: d[n]["n1"] + d[n]["n2"] + d[n]["e1"] + d[n]["e2"]
print("oracle per m", evaluate(lambda n: max((h for m, h in table[n] if h), key=lambda h: np.mean(h["f1"]))))
for mi in range(20):
    pass
for lam in [0, 0.5, 1, 2, 4, 8, 16, 32]:
    for agg in ["sumc", "meanc", "maxc"]:
        # among per-m chosen
        r1 = evaluate(lambda n: min((h for m, h in table[n] if h), key=lambda h: (h["cost"]/tot(n) + lam*h[agg])))
        # among all hypotheses at all m
        r2 = evaluate(lambda n: min((h for m, hs in d[n]["rows"] for h in hs), key=lambda h: (h["cost"]/tot(n) + lam*h[agg])))
        print(f"lam={lam} {agg}: per-m choice {r1[0]:.3f}/{r1[1]:.3f}  all-hyps {r2[0]:.3f}/{r2[1]:.3f}")
