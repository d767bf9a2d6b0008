"""Evaluate auto-m rules on hypothesis dumps with leave-one-sketch-out tuning."""
import pickle, sys, glob, itertools
import numpy as np
files = sys.argv[1:]
dumps = {f: pickle.load(open(f, "rb")) for f in files}
names = sorted(next(iter(dumps.values())))
import os
WS = [float(x) for x in os.environ.get("WS", "0 0.5 1 1.5 2 3 4 6 8").split()]
KINDS = os.environ.get("KINDS", "subs sumc").split()
def choose(D, w, kind):
    """Auto rule: per m the hypothesis with min score; then m with min normalised score (ties: smallest m)."""
    C = D["C"]; tot = D["n1"] + D["n2"] + D["e1"] + D["e2"]
    best = None
    for m, hs in D["rows"]:
        for h in hs:
            cs = np.array([C[i, j] for i, j in h["pairs"]])
            extra = np.sum(cs > m) if kind == "subs" else cs.sum()
            score = (h["cost"] + w * extra) / tot
            if best is None or score < best[0] - 1e-12:
                best = (score, h, m)
    return best
# F1 matrix: settings x sketches (mean of annotators) and per annotator
settings = list(itertools.product(files, KINDS, WS))
F = np.zeros((len(settings), len(names), 2))
M = np.zeros((len(settings), len(names)))
for k, (f, kind, w) in enumerate(settings):
    for j, n in enumerate(names):
        b = choose(dumps[f][n], w, kind)
        F[k, j] = b[1]["f1"] if b else (0, 0)
        M[k, j] = b[2] if b else np.nan
mean = F.mean(axis=2)
order = np.argsort(-mean.mean(axis=1))
for k in order[:12]:
    f, kind, w = settings[k]
    print(f"{f.split('/')[-1]:35s} {kind} w={w}: in-sample mean F1 {mean[k].mean():.3f} (mal {F[k,:,0].mean():.3f} vas {F[k,:,1].mean():.3f}) median {np.median(mean[k]):.3f}")
# LOO: choose setting on other sketches, apply to held out
loo = []; picks = []
for j in range(len(names)):
    others = [i for i in range(len(names)) if i != j]
    k = int(np.argmax(mean[:, others].mean(axis=1)))
    picks.append(settings[k][1:] + (settings[k][0].split('/')[-1],))
    loo.append(F[k, j])
loo = np.array(loo)
print(f"LOO over {len(settings)} settings: mean F1 {loo.mean():.3f} (mal {loo[:,0].mean():.3f} vas {loo[:,1].mean():.3f}) median mal {np.median(loo[:,0]):.3f} vas {np.median(loo[:,1]):.3f}")
from collections import Counter
print(Counter(picks).most_common(5))
