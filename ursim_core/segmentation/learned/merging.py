"""The learned segmenter: candidate pieces merged by the classifier, most confident pair first.

:func:`learned_labels` cuts the map into candidate pieces
(:func:`~ursim_core.segmentation.learned.pieces.candidate_pieces`), then repeatedly merges
the touching pair the merge model (:mod:`ursim_core.segmentation.learned.model`) is most
sure about, recomputing the features of the merged piece's pairs, until no pair reaches
``threshold``.

Examples
--------
>>> import numpy as np
>>> free = np.zeros((60, 130), bool)
>>> free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True  # two rooms, a door
>>> labels = learned_labels(free)
>>> int(labels[30, 30]) != int(labels[30, 100]), bool(labels[~free].any())
(True, False)
"""

from __future__ import annotations

import heapq
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError

__all__ = ["learned_labels", "agglomerate", "apply_merges", "resolve_learned_params", "LEARNED_DEFAULTS"]

#: Parameters of :func:`learned_labels`: ``model`` "default" is the shipped model, else a
#: model file path; the rest shape the candidate pieces. ``door_ratio`` 0.95 (and the
#: training's ``min_samples`` 40) were picked among 9 variants (door ratio 0.9-1.0, watershed
#: and piece minimum sizes, tree count, shrinkage, child size) by the leave-one-map-out F1 of
#: :func:`ursim_core.segmentation.learned_cv.cross_validate_learned` on the same sketches,
#: so that figure carries a small selection on the same data (door ratio 1.0, min_samples 10:
#: .833 / .764; chosen: .859 / .776, gt_lex / gt_ezvin). Choosing door ratio {0.95, 1} x
#: min_samples {10, 40} inside each fold by a leave-one-map-out on the other 17 sketches
#: (nested) gives .855 / .772: the selection adds about .004.
LEARNED_DEFAULTS: dict[str, Any] = {
    "model": "default",
    "threshold": 0.5,
    "maoris_preset": "sketch",
    "door_ratio": 0.95,
    "watershed_min_size": 100,
    "min_piece": 30,
}


def resolve_learned_params(params: dict[str, Any]) -> dict[str, Any]:
    """The defaults updated by ``params``, validated (:class:`~ursim_core.errors.ParameterError`)."""
    from ursim_core.segmentation.maoris import PRESETS

    for name in params:
        if name not in LEARNED_DEFAULTS:
            known = ", ".join(sorted(LEARNED_DEFAULTS))
            raise ParameterError(f"unknown parameter of the learned segmenter (known: {known})", field=str(name))
    values = {**LEARNED_DEFAULTS, **params}
    if not isinstance(values["model"], (str, Path)) or not str(values["model"]):
        raise ParameterError(f"must be 'default' or a model file path, got {values['model']!r}", field="model")
    for name in ("threshold", "door_ratio"):
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= float(value) <= 1.0:
            raise ParameterError(f"must be a number in [0, 1], got {value!r}", field=name)
    for name in ("watershed_min_size", "min_piece"):
        value = values[name]
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 0:
            raise ParameterError(f"must be an integer >= 0, got {value!r}", field=name)
    if values["maoris_preset"] not in PRESETS:
        known = ", ".join(sorted(PRESETS))
        raise ParameterError(
            f"unknown MAORIS preset {values['maoris_preset']!r} (known: {known})", field="maoris_preset"
        )
    return {
        "model": str(values["model"]),
        "threshold": float(values["threshold"]),
        "maoris_preset": str(values["maoris_preset"]),
        "door_ratio": float(values["door_ratio"]),
        "watershed_min_size": int(values["watershed_min_size"]),
        "min_piece": int(values["min_piece"]),
    }


def agglomerate(graph, model, *, threshold: float = 0.5) -> dict[int, int]:
    """Merge touching pieces of ``graph`` (:class:`~ursim_core.segmentation.learned.features.PieceGraph`,
    changed in place), most probable pair first, while the probability is >= ``threshold``.

    Returns
    -------
    dict of int to int
        Each merged-away piece -> the piece it went into (follow the chain to the end).
    """
    heap: list[tuple[float, int, int, int, int]] = []
    version = dict.fromkeys(graph.pieces, 0)

    def push(pairs):
        if not pairs:
            return
        for (a, b), p in zip(pairs, model.predict(graph.features(pairs)).tolist()):
            if p >= threshold:
                heapq.heappush(heap, (-p, a, b, version[a], version[b]))

    push(graph.pairs())
    into: dict[int, int] = {}
    while heap:
        _, a, b, va, vb = heapq.heappop(heap)
        if a not in graph.pieces or b not in graph.pieces or version[a] != va or version[b] != vb:
            continue  # stale: one side merged since
        keep, gone = (a, b) if graph.pieces[a][0] >= graph.pieces[b][0] else (b, a)
        graph.merge(keep, gone)
        into[gone] = keep
        version[keep] += 1
        push(sorted((min(keep, o), max(keep, o)) for o in graph.neighbours[keep]))
    return into


def apply_merges(pieces: np.ndarray, into: dict[int, int]) -> np.ndarray:
    """The piece label image with every merged-away piece relabelled as the piece it ended in
    (``into`` as :func:`agglomerate` returns it); labels are not renumbered."""
    count = int(pieces.max()) + 1
    lookup = np.arange(count, dtype=np.int32)
    for piece in into:
        target = piece
        while target in into:
            target = into[target]
        lookup[piece] = target
    return lookup[pieces]


def learned_labels(free: np.ndarray, **params: Any) -> np.ndarray:
    """Segment a free-space mask by learned merging of candidate pieces.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True = free space.
    model : str, keyword-only
        "default" (the model shipped in the package) or a model file.
    threshold : float, keyword-only
        Pairs merge while the model's probability is at least this.
    maoris_preset, door_ratio, watershed_min_size, min_piece : keyword-only
        The candidate pieces (:func:`~ursim_core.segmentation.learned.pieces.candidate_pieces`).

    Returns
    -------
    ndarray of int32
        0 = obstacle; regions 1..N in the raster order of their first pixel.

    Examples
    --------
    >>> free = np.zeros((60, 130), bool)
    >>> free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True  # two rooms, a door
    >>> labels = learned_labels(free)
    >>> int(labels[30, 30]), int(labels[30, 100]), int(labels[30, 65])  # left room, right room, door
    (1, 2, 3)
    >>> int(learned_labels(free, threshold=0.0).max())  # every touching pair merges
    1
    """
    from ursim_core.segmentation.learned.features import PieceGraph
    from ursim_core.segmentation.learned.model import default_merge_model, load_merge_model
    from ursim_core.segmentation.learned.pieces import candidate_pieces
    from ursim_core.segmentation.watershed import in_raster_order

    options = resolve_learned_params(params)
    model = default_merge_model() if options["model"] == "default" else load_merge_model(options["model"])
    pieces = candidate_pieces(
        free,
        maoris_preset=options["maoris_preset"],
        door_ratio=options["door_ratio"],
        watershed_min_size=options["watershed_min_size"],
        min_piece=options["min_piece"],
    )
    graph = PieceGraph.from_pieces(pieces)
    into = agglomerate(graph, model, threshold=options["threshold"])
    return in_raster_order(apply_merges(pieces.labels, into))
