"""The merge classifier: boosted depth-2 trees, stored as JSON, evaluated with numpy.

A model is ``base`` plus the sum over trees of one leaf value each, a log-odds that two
touching pieces belong to one region; the probability is its logistic. A tree tests
``x[feature] <= threshold`` at its root, then at the root's left or right child, and ends
in one of four leaves (left-left, left-right, right-left, right-right). :func:`fit_merge_model`
trains one by gradient boosting of the logistic loss (Newton steps, thresholds among the
training values' quantiles), deterministic: no randomness, ties go to the first feature
and threshold.

File format (``format: "ursim-merge-model"``, ``version: 1``)::

    {"format": "ursim-merge-model", "version": 1, "features": [names...], "base": float,
     "trees": [{"feature": [root, left, right], "threshold": [root, left, right],
                "leaf": [ll, lr, rl, rr]}, ...],
     "metadata": {...}}

Examples
--------
>>> x = np.array([[0.0], [1.0], [2.0], [3.0]])
>>> model = fit_merge_model(x, np.array([0.0, 0.0, 1.0, 1.0]), features=("f",), trees=20, min_samples=1)
>>> (model.predict(x) > 0.5).tolist()
[False, False, True, True]
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.errors import SegmentationError

__all__ = ["MergeModel", "fit_merge_model", "load_merge_model", "default_merge_model", "MODEL_FORMAT"]

MODEL_FORMAT = "ursim-merge-model"
_DEFAULT_FILE = Path(__file__).with_name("merge_model.json")


@dataclass(frozen=True, eq=False)
class MergeModel:
    """Boosted depth-2 trees over named features.

    Attributes
    ----------
    features : tuple of str
        Column names of the inputs, in order.
    base : float
        Log-odds before any tree.
    feature, threshold : ndarray, shape (trees, 3)
        Per tree the tested column and threshold at the root, its left and its right child.
    leaf : ndarray, shape (trees, 4)
        Log-odds added by each leaf.
    metadata : dict
        Provenance, licence and training settings (kept as loaded).
    """

    features: tuple[str, ...]
    base: float
    feature: np.ndarray
    threshold: np.ndarray
    leaf: np.ndarray
    metadata: dict[str, Any] = field(default_factory=dict)

    def log_odds(self, x: np.ndarray) -> np.ndarray:
        """Log-odds of merging for rows of ``x`` (shape (n, features))."""
        x = np.asarray(x, np.float64)
        if x.ndim != 2 or x.shape[1] != len(self.features):
            raise SegmentationError(f"the merge model takes {len(self.features)} features, got shape {x.shape}")
        rows = np.arange(len(x))[:, None]
        root = x[rows, self.feature[None, :, 0]] > self.threshold[None, :, 0]  # (n, trees)
        child = 1 + root.astype(np.intp)
        tested = np.take_along_axis(self.feature[None].repeat(len(x), 0), child[..., None], 2)[..., 0]
        limit = np.take_along_axis(self.threshold[None].repeat(len(x), 0), child[..., None], 2)[..., 0]
        second = x[rows, tested] > limit
        index = 2 * root + second
        return self.base + np.take_along_axis(self.leaf[None].repeat(len(x), 0), index[..., None], 2)[..., 0].sum(1)

    def predict(self, x: np.ndarray) -> np.ndarray:
        """Probability that each pair belongs to one region."""
        return 1.0 / (1.0 + np.exp(-self.log_odds(x)))

    def to_dict(self) -> dict[str, Any]:
        trees = [
            {"feature": f.tolist(), "threshold": t.tolist(), "leaf": v.tolist()}
            for f, t, v in zip(self.feature, self.threshold, self.leaf)
        ]
        return {
            "format": MODEL_FORMAT,
            "version": 1,
            "features": list(self.features),
            "base": self.base,
            "trees": trees,
            "metadata": self.metadata,
        }

    def save(self, path: str | Path) -> None:
        """Write the model as JSON, atomically."""
        from ursim_core.io.atomic import atomic_write_bytes

        text = json.dumps(self.to_dict(), indent=1) + "\n"
        atomic_write_bytes(Path(path), text.encode("utf-8"))

    @classmethod
    def from_dict(cls, data: Any, *, path: str | Path | None = None) -> MergeModel:
        """Validate and build; :class:`~ursim_core.errors.SegmentationError` names the problem."""

        def fail(problem: str, where: str | None = None):
            return SegmentationError(problem, path=path, field=where)

        if not isinstance(data, dict) or data.get("format") != MODEL_FORMAT:
            raise fail(f'not a merge model (expected "format": "{MODEL_FORMAT}")')
        if data.get("version") != 1:
            raise fail(f"unsupported merge model version {data.get('version')!r} (known: 1)", "version")
        names = data.get("features")
        if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
            raise fail("must be a non-empty list of feature names", "features")
        base = data.get("base")
        if isinstance(base, bool) or not isinstance(base, (int, float)) or not math.isfinite(base):
            raise fail("must be a finite number", "base")
        trees = data.get("trees")
        if not isinstance(trees, list):
            raise fail("must be a list of trees", "trees")
        arrays = {"feature": [], "threshold": [], "leaf": []}
        for i, tree in enumerate(trees):
            for key, size in (("feature", 3), ("threshold", 3), ("leaf", 4)):
                values = tree.get(key) if isinstance(tree, dict) else None
                if (
                    not isinstance(values, list)
                    or len(values) != size
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
                    or not all(math.isfinite(v) for v in values)
                ):
                    raise fail(f"must be a list of {size} finite numbers", f"trees[{i}].{key}")
                if key == "feature" and not all(float(v).is_integer() and 0 <= v < len(names) for v in values):
                    raise fail(f"feature indices must be integers in 0..{len(names) - 1}", f"trees[{i}].feature")
                arrays[key].append(values)
        metadata = data.get("metadata", {})
        if not isinstance(metadata, dict):
            raise fail("must be an object", "metadata")
        return cls(
            features=tuple(names),
            base=float(base),
            feature=np.array(arrays["feature"], np.intp).reshape(-1, 3),
            threshold=np.array(arrays["threshold"], np.float64).reshape(-1, 3),
            leaf=np.array(arrays["leaf"], np.float64).reshape(-1, 4),
            metadata=metadata,
        )


#: Largest model file read: the shipped one is about 20 kB; a thousand trees take 200 kB.
MAX_MODEL_BYTES = 16 * 1024**2


def load_merge_model(path: str | Path) -> MergeModel:
    """Read a model file; :class:`~ursim_core.errors.SegmentationError` naming the file
    when it is missing, not a regular file (a pipe is never opened), larger than
    :data:`MAX_MODEL_BYTES`, not JSON (or JSON nested too deep or with numbers out of range),
    or not a valid model."""
    from ursim_core.io.reading import read_json_file

    path = Path(path)
    data = read_json_file(path, max_bytes=MAX_MODEL_BYTES, error=SegmentationError, what="merge model file")
    return MergeModel.from_dict(data, path=path)


_CACHE: dict[str, MergeModel] = {}


def default_merge_model() -> MergeModel:
    """The model shipped in the package (``merge_model.json``), loaded once."""
    if "default" not in _CACHE:
        _CACHE["default"] = load_merge_model(_DEFAULT_FILE)
    return _CACHE["default"]


def _thresholds(column: np.ndarray, bins: int) -> np.ndarray:
    """Candidate split points: midpoints between neighbouring distinct quantiles."""
    values = np.unique(np.quantile(column, np.linspace(0.0, 1.0, bins + 1)))
    return (values[:-1] + values[1:]) / 2.0


def _best_split(binned, gradient, hessian, rows, n_bins, reg, min_samples):
    """(gain, feature, bin) of the best split of ``rows``, or None."""
    g, h = gradient[rows], hessian[rows]
    total_g, total_h = g.sum(), h.sum()
    best = None
    parent = total_g * total_g / (total_h + reg)
    for f in range(binned.shape[1]):
        column = binned[rows, f]
        left_g = np.cumsum(np.bincount(column, weights=g, minlength=n_bins[f] + 1))[:-1]
        left_h = np.cumsum(np.bincount(column, weights=h, minlength=n_bins[f] + 1))[:-1]
        left_n = np.cumsum(np.bincount(column, minlength=n_bins[f] + 1))[:-1]
        right_g, right_h = total_g - left_g, total_h - left_h
        valid = (left_n >= min_samples) & (len(rows) - left_n >= min_samples)
        if not valid.any():
            continue
        gain = left_g**2 / (left_h + reg) + right_g**2 / (right_h + reg) - parent
        gain[~valid] = -np.inf
        k = int(np.argmax(gain))
        if gain[k] > 1e-12 and (best is None or gain[k] > best[0]):
            best = (float(gain[k]), f, k)
    return best


def fit_merge_model(
    x: np.ndarray,
    y: np.ndarray,
    *,
    features: tuple[str, ...],
    weights: np.ndarray | None = None,
    trees: int = 150,
    learning_rate: float = 0.1,
    bins: int = 32,
    reg: float = 1.0,
    min_samples: int = 10,
    metadata: dict[str, Any] | None = None,
) -> MergeModel:
    """Gradient boosting of depth-2 trees on the logistic loss.

    Parameters
    ----------
    x : ndarray, shape (samples, features)
    y : ndarray, shape (samples,)
        Targets in [0, 1] (soft targets allowed: the share of annotators who merge).
    features : tuple of str, keyword-only
        Column names.
    weights : ndarray, optional
        Sample weights (default 1).
    trees, learning_rate, bins, reg, min_samples : keyword-only
        Number of trees, shrinkage, candidate thresholds per feature, L2 penalty of the leaf
        values, fewest samples in a child of a split.
    """
    x = np.asarray(x, np.float64)
    y = np.asarray(y, np.float64)
    w = np.ones(len(y)) if weights is None else np.asarray(weights, np.float64)
    cuts = [_thresholds(x[:, f], bins) for f in range(x.shape[1])]
    binned = np.stack([np.searchsorted(cuts[f], x[:, f], side="left") for f in range(x.shape[1])], axis=1)
    n_bins = [len(c) for c in cuts]
    mean = float(np.clip(np.average(y, weights=w), 1e-6, 1 - 1e-6))
    base = math.log(mean / (1.0 - mean))
    score = np.full(len(y), base)
    all_rows = np.arange(len(y))
    feature, threshold, leaf = [], [], []
    for _ in range(trees):
        p = 1.0 / (1.0 + np.exp(-score))
        gradient, hessian = w * (p - y), w * np.maximum(p * (1.0 - p), 1e-12)
        root = _best_split(binned, gradient, hessian, all_rows, n_bins, reg, min_samples)
        if root is None:
            break
        _, f0, k0 = root
        sides = [all_rows[binned[:, f0] <= k0], all_rows[binned[:, f0] > k0]]
        tree_f, tree_t, tree_leaf = [f0], [float(cuts[f0][k0])], []
        for rows in sides:
            split = _best_split(binned, gradient, hessian, rows, n_bins, reg, min_samples)
            # No useful split: test the root's feature again at its own threshold (one leaf used).
            f, t = (split[1], float(cuts[split[1]][split[2]])) if split else (f0, float(cuts[f0][k0]))
            tree_f.append(f)
            tree_t.append(t)
            for part in (rows[x[rows, f] <= t], rows[x[rows, f] > t]):
                value = -gradient[part].sum() / (hessian[part].sum() + reg) * learning_rate if part.size else 0.0
                tree_leaf.append(round(float(value), 6))
                score[part] += tree_leaf[-1]
        feature.append(tree_f)
        threshold.append(tree_t)
        leaf.append(tree_leaf)
    return MergeModel(
        features=tuple(features),
        base=round(base, 6),
        feature=np.array(feature, np.intp).reshape(-1, 3),
        threshold=np.array(threshold, np.float64).reshape(-1, 3),
        leaf=np.array(leaf, np.float64).reshape(-1, 4),
        metadata=dict(metadata or {}),
    )
