import pickle, sys
import numpy as np
d = pickle.load(open(sys.argv[1], "rb"))
for n in sorted(d):
    D = d[n]; tot = D["n1"] + D["n2"] + D["e1"] + D["e2"]
    line = []
    for m, hs in D["rows"]:
        if not hs: line.append("   -   "); continue
        b = min(hs, key=lambda h: h["cost"])
        line.append(f"{np.mean(b['f1']):.2f}/{b['cost']/tot:.2f}")
    print(n, D["n1"], D["e1"], " ".join(line[::2]))
