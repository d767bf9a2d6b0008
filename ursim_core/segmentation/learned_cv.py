"""Leave-one-map-out figures of the learned segmenter (:mod:`ursim_core.segmentation.learned`).

For each map of the benchmark, a merge model is trained on the pairs of the *other* maps
(both annotators) and the map is segmented with it and scored against each annotator
(:func:`ursim_core.segmentation.scoring.score_segmentation`): the ``cv_f1`` of the rows.
The model trained on all maps (the one shipped, given the same settings) scored on each
map gives ``in_sample_f1``. The result is a
:class:`~ursim_core.segmentation.presets_cv.CrossValidation`, so its rows and summary sit
beside those of the presets (:func:`ursim_core.segmentation.presets_cv.cross_validate`).

Examples
--------
>>> from ursim_core.segmentation.presets_cv import BenchmarkMap
>>> import numpy as np
>>> free = np.zeros((60, 130), bool)
>>> free[5:55, 5:60] = free[5:55, 70:125] = free[27:33, 60:70] = True
>>> truth = np.where(free, 1 + (np.arange(130) >= 65), 0).astype(np.int32)
>>> maps = [BenchmarkMap(f"m{i}", free, {"gt": truth}) for i in range(2)]
>>> cv = cross_validate_learned(maps)
>>> len(cv.rows), cv.rows[0]["cv_choice"]
(2, 'model trained without m0')
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["cross_validate_learned", "LEARNED_PRESET_NAME"]

LEARNED_PRESET_NAME = "learned"


def cross_validate_learned(
    benchmark=None,
    *,
    dataset_root: str | Path | None = None,
    maps: str = "sketches",
    params: dict[str, Any] | None = None,
    training: dict[str, Any] | None = None,
):
    """In-sample and leave-one-map-out F1 of learned merging, per map and annotator.

    Parameters
    ----------
    benchmark : list of BenchmarkMap, optional
        Maps with ground truth (:func:`ursim_core.segmentation.presets_cv.load_benchmark`);
        loaded from ``dataset_root`` / ``maps`` when not given.
    dataset_root : str or Path, optional
        The shared datasets folder (needed when ``benchmark`` is not given).
    maps : {"sketches", "robot_maps"}
    params : dict, optional
        Parameters of the candidate pieces and the merging
        (:data:`~ursim_core.segmentation.learned.merging.LEARNED_DEFAULTS`; ``model`` is ignored:
        the models are trained here).
    training : dict, optional
        Boosting settings (:data:`~ursim_core.segmentation.learned.training.TRAINING_DEFAULTS`).

    Returns
    -------
    CrossValidation
        Rows with ``preset`` "learned", ``cv_choice`` naming the map left out of training,
        and the annotators' agreement (sketches).
    """
    from ursim_core.errors import ParameterError
    from ursim_core.segmentation.learned.features import PieceGraph
    from ursim_core.segmentation.learned.merging import agglomerate, apply_merges, resolve_learned_params
    from ursim_core.segmentation.learned.pieces import candidate_pieces
    from ursim_core.segmentation.learned.training import map_pairs, train_merge_model
    from ursim_core.segmentation.presets_cv import CrossValidation, cross_validate, load_benchmark
    from ursim_core.segmentation.scoring import score_segmentation

    if benchmark is None:
        if dataset_root is None:
            raise ParameterError("the datasets folder is needed", field="dataset_root")
        benchmark = load_benchmark(dataset_root, maps)
    options = resolve_learned_params(params or {})
    piece_options = {k: options[k] for k in ("maoris_preset", "door_ratio", "watershed_min_size", "min_piece")}
    pieces = [candidate_pieces(item.free, **piece_options) for item in benchmark]
    samples = [map_pairs(p, item.ground_truths) for p, item in zip(pieces, benchmark)]

    def scores(model, m: int) -> dict[str, float]:
        graph = PieceGraph.from_pieces(pieces[m])
        into = agglomerate(graph, model, threshold=options["threshold"])
        labels = apply_merges(pieces[m].labels, into)
        return {a: score_segmentation(labels, gt).f1 for a, gt in benchmark[m].ground_truths.items()}

    settings = dict(training or {})
    everything = train_merge_model(samples, **settings)
    rows: list[dict[str, Any]] = []
    for m, item in enumerate(benchmark):
        others = [s for i, s in enumerate(samples) if i != m] or samples
        held_out = scores(train_merge_model(others, **settings), m)
        inside = scores(everything, m)
        for annotator in item.ground_truths:
            rows.append(
                {
                    "preset": LEARNED_PRESET_NAME,
                    "map": item.name,
                    "annotator": annotator,
                    "in_sample_f1": round(float(inside[annotator]), 4),
                    "cv_f1": round(float(held_out[annotator]), 4),
                    "cv_choice": f"model trained without {item.name}",
                    "chosen": "model trained on all maps",
                }
            )
    agreement = cross_validate(benchmark=benchmark, selections={}, fixed={}).agreement
    return CrossValidation(rows=rows, agreement=agreement)
