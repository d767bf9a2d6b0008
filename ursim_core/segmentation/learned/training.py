"""Training pairs for the merge model, from maps with ground-truth regions.

A piece belongs to the ground-truth region covering most of its pixels; a pair of touching
pieces is a positive (target 1) when both belong to the same region. Pairs are collected
along an *oracle* agglomeration: the pairs of the candidate pieces, then, merging positive
pairs one at a time (widest pass first, as a good merger would), every pair the merged
piece forms. So the model also sees pieces that are unions of pieces, as it meets them when
it merges for real. Each annotator's ground truth gives its own pairs, weighted
``1 / annotators``.

Examples
--------
>>> import numpy as np
>>> from ursim_core.segmentation.learned.features import PieceGraph
>>> labels = np.array([[1, 1, 2, 2, 3, 3]] * 4, np.int32)
>>> graph = PieceGraph.from_arrays(labels, labels, labels, np.ones(labels.shape, np.float32))
>>> truth = np.array([[1, 1, 1, 1, 2, 2]] * 4, np.int32)
>>> x, y = oracle_pairs(graph, labels, truth)
>>> y.tolist()                       # (1,2) same room, (2,3) not; then (1+2, 3) not
[1.0, 0.0, 0.0]
"""

from __future__ import annotations

import numpy as np

__all__ = ["oracle_pairs", "map_pairs", "train_merge_model", "TRAINING_DEFAULTS"]

#: Boosting settings of the shipped model and of the cross-validation.
TRAINING_DEFAULTS = {"trees": 150, "learning_rate": 0.1, "bins": 32, "reg": 1.0, "min_samples": 40}


def _owner(histogram: np.ndarray) -> int:
    """The ground-truth region covering most of a piece (0 when it covers none)."""
    return int(np.argmax(histogram[1:])) + 1 if histogram[1:].any() else 0


def oracle_pairs(graph, piece_labels: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Features and targets of the pairs met along an oracle agglomeration of ``graph``
    (a :class:`~ursim_core.segmentation.learned.features.PieceGraph`, changed in place).

    Pairs with a piece on no ground-truth region are left out.
    """
    from ursim_core.segmentation.learned.features import FEATURE_NAMES

    truth = np.asarray(truth, np.int64)
    count, regions = int(piece_labels.max()) + 1, int(truth.max()) + 1
    joint = np.bincount(piece_labels.astype(np.int64).ravel() * regions + truth.ravel(), minlength=count * regions)
    histogram = {p: row for p, row in enumerate(joint.reshape(count, regions)) if p in graph.pieces}
    ratio_column = FEATURE_NAMES.index("saddle_ratio")
    xs, ys = [], []

    def record(pairs):
        owners = [(_owner(histogram[a]), _owner(histogram[b])) for a, b in pairs]
        kept = [pair for pair, (oa, ob) in zip(pairs, owners) if oa and ob]
        if not kept:
            return {}
        x = graph.features(kept)
        y = np.array([float(oa == ob) for oa, ob in owners if oa and ob])
        xs.append(x)
        ys.append(y)
        return {pair: x[i, ratio_column] for i, pair in enumerate(kept) if y[i] == 1.0}

    positives = record(graph.pairs())
    while positives:
        a, b = max(sorted(positives), key=lambda pair: positives[pair])
        keep, gone = (a, b) if graph.pieces[a][0] >= graph.pieces[b][0] else (b, a)
        graph.merge(keep, gone)
        histogram[keep] = histogram[keep] + histogram.pop(gone)
        positives = {pair: r for pair, r in positives.items() if keep not in pair and gone not in pair}
        positives.update(record(sorted((min(keep, o), max(keep, o)) for o in graph.neighbours[keep])))
    if not xs:
        return np.zeros((0, len(FEATURE_NAMES))), np.zeros(0)
    return np.concatenate(xs), np.concatenate(ys)


def map_pairs(pieces, ground_truths: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Features, targets and weights of one map's pairs, over all its annotators.

    ``pieces`` are :class:`~ursim_core.segmentation.learned.pieces.CandidatePieces`.
    """
    from ursim_core.segmentation.learned.features import PieceGraph

    xs, ys, ws = [], [], []
    for truth in ground_truths.values():
        x, y = oracle_pairs(PieceGraph.from_pieces(pieces), pieces.labels, truth)
        xs.append(x)
        ys.append(y)
        ws.append(np.full(len(y), 1.0 / len(ground_truths)))
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(ws)


def train_merge_model(samples: list[tuple[np.ndarray, np.ndarray, np.ndarray]], *, metadata=None, **settings):
    """A :class:`~ursim_core.segmentation.learned.model.MergeModel` fitted on the pairs of
    several maps (each as :func:`map_pairs` gives them); ``settings`` override
    :data:`TRAINING_DEFAULTS`."""
    from ursim_core.segmentation.learned.features import FEATURE_NAMES
    from ursim_core.segmentation.learned.model import fit_merge_model

    x = np.concatenate([s[0] for s in samples])
    y = np.concatenate([s[1] for s in samples])
    w = np.concatenate([s[2] for s in samples])
    return fit_merge_model(
        x, y, features=FEATURE_NAMES, weights=w, metadata=metadata, **{**TRAINING_DEFAULTS, **settings}
    )
