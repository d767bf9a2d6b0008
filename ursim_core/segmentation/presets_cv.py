"""Leave-one-map-out figures of the presets chosen on data (``maoris_segmentation``).

A preset chosen on the maps it is scored on looks better than it will on a new map. Here a
data-chosen preset is a *selection rule*: the candidate of its grid with the best mean F1
(:func:`ursim_core.segmentation.scoring.score_segmentation`) over the training maps and
all their annotators. :func:`cross_validate` reports, per map and per annotator, the
in-sample F1 (the candidate chosen on all maps) and the leave-one-map-out F1 (the candidate
chosen on the other maps, scored on the left-out one), and for sketches the annotators'
agreement (each ground truth scored against the other, the mean of both directions), the
reference line a segmenter cannot be expected to beat. Presets not chosen on these maps
(``fixed``) are scored as they are: their in-sample and cross-validated figures are equal.

Examples
--------
>>> grid = {"tiny": [Candidate("maoris", {"doors": 40}), Candidate("maoris", {"doors": 60})]}
>>> sorted(grid)                                  # a selection: one preset, two candidates
['tiny']
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "Candidate",
    "BenchmarkMap",
    "CrossValidation",
    "load_benchmark",
    "default_selections",
    "default_fixed",
    "score_candidates",
    "cross_validate",
]


@dataclass(frozen=True)
class Candidate:
    """A segmenter and its parameters (a key of ``SEGMENTERS`` and its full parameters)."""

    method: str
    params: dict[str, Any] = field(default_factory=dict)

    def label(self) -> str:
        return f"{self.method}(" + ", ".join(f"{k}={v}" for k, v in sorted(self.params.items())) + ")"


@dataclass(frozen=True)
class BenchmarkMap:
    """One map of the benchmark: its name, free-space mask and ground truths by annotator."""

    name: str
    free: np.ndarray
    ground_truths: dict[str, np.ndarray]


def load_benchmark(dataset_root: str | Path, maps: str = "sketches") -> list[BenchmarkMap]:
    """The maps of ``maoris_segmentation/<maps>`` with their ground truths.

    ``maps`` is ``"sketches"`` (annotators ``gt_lex`` and ``gt_ezvin``) or ``"robot_maps"``
    (``gt``). Free space = grey > 250, as the MAORIS evaluation.
    """
    from ursim_core.errors import ParameterError
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation.scoring import gt_labels_from_separator_image

    if maps not in ("sketches", "robot_maps"):
        raise ParameterError(f"must be 'sketches' or 'robot_maps', got {maps!r}", field="maps")
    root = Path(dataset_root) / "maoris_segmentation" / maps
    annotators = ("gt_lex", "gt_ezvin") if maps == "sketches" else ("gt",)
    return [
        BenchmarkMap(
            name=path.stem,
            free=load_map(path).free,
            ground_truths={a: gt_labels_from_separator_image(root / a / path.name) for a in annotators},
        )
        for path in sorted((root / "maps").glob("*.png"))
    ]


def _grid(method: str, **axes: list) -> list[Candidate]:
    names = sorted(axes)
    return [Candidate(method, dict(zip(names, values))) for values in itertools.product(*(axes[n] for n in names))]


def default_selections(maps: str = "sketches") -> dict[str, list[Candidate]]:
    """The selection rules of the presets chosen on data, by preset name.

    Sketches: ``sketch``, the MAORIS grid it is chosen from (threshold, doors, quantum,
    ripples, small_after; :mod:`ursim_core.segmentation.maoris.params`), and
    ``sketch-t-doors``, the threshold x doors grid of the earlier ``sketch``. Robot maps:
    ``watershed`` (door ratio x minimum size, its defaults'
    :data:`~ursim_core.segmentation.watershed.WATERSHED_DEFAULTS`) and the MAORIS
    threshold x doors grid.
    """
    if maps == "sketches":
        return {
            "sketch": _grid(
                "maoris",
                threshold=[0.15, 0.20, 0.25],
                doors=[50, 100],
                quantum=[5, 8],
                ripples=[40, 45],
                small_after=[0, 100],
            ),
            "sketch-t-doors": _grid("maoris", threshold=[0.25, 0.30, 0.35, 0.40, 0.50], doors=[40, 50, 60]),
        }
    return {
        "watershed": _grid("watershed", door_ratio=[0.7, 0.75, 0.8, 0.85, 0.9], min_size=[50, 100, 200]),
        "maoris-t-doors": _grid("maoris", threshold=[0.25, 0.30, 0.40, 0.50], doors=[40, 60]),
    }


def default_fixed(maps: str = "sketches") -> dict[str, Candidate]:
    """Presets not chosen on these maps (the original code's parameter sets)."""
    from ursim_core.segmentation.maoris.params import PRESETS

    names = ("default", "icra") if maps == "sketches" else ("default", "robot", "icra")
    return {name: Candidate("maoris", PRESETS[name].to_dict()) for name in names}


def score_candidates(benchmark: list[BenchmarkMap], candidates: list[Candidate]) -> np.ndarray:
    """F1 of every candidate on every map against every annotator: shape
    (candidates, maps, annotators), annotators in the order of the first map's."""
    from ursim_core.segmentation.interface import SEGMENTERS, resolve_params
    from ursim_core.segmentation.scoring import score_segmentation

    annotators = list(benchmark[0].ground_truths)
    out = np.zeros((len(candidates), len(benchmark), len(annotators)))
    for c, candidate in enumerate(candidates):
        params = resolve_params(candidate.method, None, candidate.params)
        for m, item in enumerate(benchmark):
            labels = SEGMENTERS[candidate.method](item.free, **params)
            for a, annotator in enumerate(annotators):
                out[c, m, a] = score_segmentation(labels, item.ground_truths[annotator]).f1
    return out


@dataclass(frozen=True)
class CrossValidation:
    """Figures of :func:`cross_validate`.

    Attributes
    ----------
    rows : list of dict
        Per preset, map and annotator: ``preset``, ``map``, ``annotator``, ``in_sample_f1``,
        ``cv_f1``, ``cv_choice`` (the candidate chosen without that map) and ``chosen``
        (the candidate chosen on all maps).
    agreement : list of dict
        Per map (sketches): ``map``, ``f1`` of the annotators against each other.
    """

    rows: list[dict[str, Any]]
    agreement: list[dict[str, Any]]

    def summary(self) -> list[dict[str, Any]]:
        """Per preset and annotator: mean and worst in-sample and cross-validated F1,
        then the annotators' agreement as a row of its own."""
        out = []
        keys = dict.fromkeys((row["preset"], row["annotator"]) for row in self.rows)
        for preset, annotator in keys:
            rows = [r for r in self.rows if r["preset"] == preset and r["annotator"] == annotator]
            inside, cv = [r["in_sample_f1"] for r in rows], [r["cv_f1"] for r in rows]
            out.append(
                {
                    "preset": preset,
                    "annotator": annotator,
                    "maps": len(rows),
                    "in_sample_mean": round(float(np.mean(inside)), 3),
                    "in_sample_worst": round(float(np.min(inside)), 3),
                    "cv_mean": round(float(np.mean(cv)), 3),
                    "cv_worst": round(float(np.min(cv)), 3),
                    "chosen": rows[0]["chosen"],
                }
            )
        if self.agreement:
            f1 = [r["f1"] for r in self.agreement]
            out.append(
                {
                    "preset": "annotators' agreement",
                    "annotator": "each other",
                    "maps": len(f1),
                    "in_sample_mean": round(float(np.mean(f1)), 3),
                    "in_sample_worst": round(float(np.min(f1)), 3),
                    "cv_mean": round(float(np.mean(f1)), 3),
                    "cv_worst": round(float(np.min(f1)), 3),
                    "chosen": "",
                }
            )
        return out


def _annotator_agreement(benchmark: list[BenchmarkMap]) -> list[dict[str, Any]]:
    from ursim_core.segmentation.scoring import score_segmentation

    rows = []
    for item in benchmark:
        truths = list(item.ground_truths.values())
        if len(truths) != 2:
            return []
        both = (score_segmentation(truths[0], truths[1]).f1, score_segmentation(truths[1], truths[0]).f1)
        rows.append({"map": item.name, "f1": round(float(np.mean(both)), 4)})
    return rows


def cross_validate(
    dataset_root: str | Path | None = None,
    *,
    maps: str = "sketches",
    selections: dict[str, list[Candidate]] | None = None,
    fixed: dict[str, Candidate] | None = None,
    benchmark: list[BenchmarkMap] | None = None,
) -> CrossValidation:
    """In-sample and leave-one-map-out F1 of presets, per map and annotator.

    Parameters
    ----------
    dataset_root : str or Path, optional
        The shared datasets folder (default: :func:`ursim_core.evaluation.datasets`'s rule
        is the caller's; here it is required unless ``benchmark`` is given).
    maps : {"sketches", "robot_maps"}
    selections : dict of name to list of Candidate, optional
        Presets chosen on data, each by its grid (default :func:`default_selections`).
    fixed : dict of name to Candidate, optional
        Presets not chosen on these maps (default :func:`default_fixed`).
    benchmark : list of BenchmarkMap, optional
        Already loaded maps (:func:`load_benchmark`).
    """
    from ursim_core.errors import ParameterError

    if benchmark is None:
        if dataset_root is None:
            raise ParameterError("the datasets folder is needed", field="dataset_root")
        benchmark = load_benchmark(dataset_root, maps)
    selections = default_selections(maps) if selections is None else selections
    fixed = default_fixed(maps) if fixed is None else fixed
    annotators = list(benchmark[0].ground_truths)
    rows: list[dict[str, Any]] = []
    for name, candidates in {**selections, **{k: [v] for k, v in fixed.items()}}.items():
        f1 = score_candidates(benchmark, candidates)  # (candidates, maps, annotators)
        per_map = f1.mean(axis=2)  # both annotators weigh alike
        chosen = int(np.argmax(per_map.sum(axis=1)))
        for m, item in enumerate(benchmark):
            training = np.delete(per_map, m, axis=1).sum(axis=1) if len(benchmark) > 1 else per_map[:, 0]
            choice = int(np.argmax(training))
            for a, annotator in enumerate(annotators):
                rows.append(
                    {
                        "preset": name,
                        "map": item.name,
                        "annotator": annotator,
                        "in_sample_f1": round(float(f1[chosen, m, a]), 4),
                        "cv_f1": round(float(f1[choice, m, a]), 4),
                        "cv_choice": candidates[choice].label(),
                        "chosen": candidates[chosen].label(),
                    }
                )
    return CrossValidation(rows=rows, agreement=_annotator_agreement(benchmark))
