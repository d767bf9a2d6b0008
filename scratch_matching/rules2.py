import pickle, sys
import numpy as np
d = pickle.load(open(sys.argv[1], "rb"))
names = sorted(d)
tot = lambda n: d[n]["n1"] + d[n]["n2"] + d[n]["e1"] + d[n]["e2"]
def allh(n):
    C = d[n]["C"]
    for m, hs in d[n]["rows"]:
        for h in hs:
            i, j = h["pairs"][0]
            h["seedc"] = C[i, j]
            h["m"] = m
            yield h
def evaluate(rule):
    f = [np.mean(rule(n)["f1"]) for n in names]
    return np.mean(f), np.median(f)
for lam in [0, 0.25, 0.5, 1, 2, 3, 4, 6, 8]:
    r = evaluate(lambda n: min(allh(n), key=lambda h: (h["cost"]/tot(n) + lam*h["seedc"], h["seedc"])))
    r2 = evaluate(lambda n: min(allh(n), key=lambda h: (h["cost"]/tot(n) + lam*h["seedc"] + 0*h["meanc"], h["meanc"])))
    print(f"lam={lam}: seedc {r[0]:.3f}/{r[1]:.3f}   tie meanc {r2[0]:.3f}/{r2[1]:.3f}")
