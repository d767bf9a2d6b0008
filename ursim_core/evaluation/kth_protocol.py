"""The KTH sketch-matching experiment: segmentations, reference cliques and F1 tables.

Used by the matching benchmark (``ursim_core.bench.matching``), the dataset regression test and
the studies behind the defaults (``ursim_core.matching.auto_m``). The data (18 KTH sketches, the
metric model, ground truth by two annotators) is read from the datasets folder and never copied.

Protocol (``original_code.md`` §1.1, §1.13; correct scoring of ``ursim_core.evaluation.scoring``):

- Sketches and the model are loaded with :func:`ursim_core.io.maps.load_map` and segmented with MAORIS
  (:func:`ursim_core.segmentation.segment`). The *recommended* pipeline binarises at > 250 and uses
  the ``"default"`` preset (t = 0.25, doors 40, the parameters the ground truth was clicked on) for
  both maps; the *released* pipeline uses every non-zero pixel as free and the ``"ursim-released"``
  preset (t = 0.50) for both, as the released driver did.
- Ground-truth points map to regions of the segmentation being matched by
  :func:`ursim_core.correspondences.regions_at_points` (10 px tolerance).
- F1 is computed per sketch and annotator with ``score_matches`` (correct mode by default:
  pairs counted once, cliques with an empty side ignored; ``legacy="fnfix"`` reproduces the
  released scorer with the flag initialised).
"""

from __future__ import annotations

import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = [
    "ANNOTATORS",
    "PIPELINES",
    "KthCases",
    "kth_pairs",
    "reference_cliques",
    "score_pairs",
    "f1_table",
    "summarise",
    "accuracy_report",
]

ANNOTATORS = ("malcolm", "vasiliki")
#: Map loading + segmentation per pipeline: (nonzero_free, MAORIS preset).
PIPELINES = {
    "recommended": (False, "default"),
    "released": (True, "ursim-released"),
}


def reference_cliques(labels: np.ndarray, metric_labels: np.ndarray, cliques, *, tolerance: float = 10) -> list:
    """Reference cliques as (sketch region set, metric region set), points dropped when unmapped.

    Parameters
    ----------
    labels, metric_labels : ndarray
        Label images of the sketch and the metric map.
    cliques : iterable of Clique
        From :func:`ursim_core.correspondences.load_dat` (``sketch_points``, ``metric_points``).

    Examples
    --------
    >>> from ursim_core.correspondences import Clique
    >>> sketch = np.array([[1, 1, 2]]); metric = np.array([[5, 6, 6]])
    >>> reference_cliques(sketch, metric, [Clique(id=1, sketch_points=[(0, 2)], metric_points=[(0, 0)])])
    [({2}, {5})]
    """
    from ursim_core.correspondences import Correspondences, assign_regions

    assigned = assign_regions(Correspondences(cliques=tuple(cliques)), labels, metric_labels, tolerance=tolerance)
    return [(set(c.sketch_regions), set(c.metric_regions)) for c in assigned.cliques]


def score_pairs(pairs, reference, *, legacy=False):
    """Score matched pairs against reference cliques (``evaluation_scoring.score_matches``)."""
    from ursim_core.evaluation.scoring import score_matches

    return score_matches(list(pairs), reference, legacy=legacy)


@dataclass
class KthCases:
    """Segmented KTH maps and ground truth for one pipeline.

    Attributes
    ----------
    pipeline : str
        Key of :data:`PIPELINES`.
    sketches : dict
        Sketch name ('00', ...) -> Segmentation.
    model : Segmentation
    references : dict
        annotator -> sketch name -> list of (sketch regions, metric regions).
    segmentation_seconds : float
    """

    pipeline: str
    sketches: dict
    model: object
    references: dict
    segmentation_seconds: float = 0.0
    ground_truth: dict = field(default_factory=dict)

    def reference(self, annotator: str, name: str) -> list:
        return self.references[annotator][name]


_CACHE: dict = {}


def _segment_file(path: Path, nonzero_free: bool, preset: str):
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import segment

    return segment(load_map(path, nonzero_free=nonzero_free), preset=preset)


def kth_pairs(root, *, pipeline: str = "recommended", sketches: Sequence[str] | None = None) -> KthCases:
    """Load, segment and reference the KTH sketches for one pipeline (cached per process).

    Parameters
    ----------
    root : Path
        The datasets folder (``ursim_core.evaluation.datasets.dataset_root()``).
    pipeline : {'recommended', 'released'}
    sketches : sequence of str, optional
        Subset of sketch names; default all 18.
    """
    import time

    from ursim_core.correspondences import load_dat

    root = Path(root)
    folder = root / "ursim_kth_sketches"
    nonzero_free, preset = PIPELINES[pipeline]
    names = sorted(p.stem for p in (folder / "sketches").glob("*.png"))
    if sketches is not None:
        names = [n for n in names if n in set(sketches)]
    start = time.perf_counter()
    key = (str(folder), pipeline)
    cached = _CACHE.setdefault(key, {})
    if "model" not in cached:
        cached["model"] = _segment_file(folder / "model" / "model_simple.png", nonzero_free, preset)
    for name in names:
        if name not in cached:
            cached[name] = _segment_file(folder / "sketches" / f"{name}.png", nonzero_free, preset)
    model = cached["model"]
    segmentations = {name: cached[name] for name in names}
    references = {}
    ground_truth = {}
    for annotator in ANNOTATORS:
        references[annotator] = {}
        ground_truth[annotator] = {}
        for name in names:
            path = folder / "gt_correspondences" / annotator / f"gt_{name}_model_simple.dat"
            cliques = load_dat(path).cliques
            ground_truth[annotator][name] = cliques
            references[annotator][name] = reference_cliques(segmentations[name].labels, model.labels, cliques)
    return KthCases(
        pipeline=pipeline,
        sketches=segmentations,
        model=model,
        references=references,
        segmentation_seconds=time.perf_counter() - start,
        ground_truth=ground_truth,
    )


def f1_table(
    cases: KthCases,
    config,
    m_values: Sequence[float] | None = None,
    *,
    legacy=False,
    prepared_hook: Callable | None = None,
) -> dict:
    """F1 of every sketch, annotator and m.

    Parameters
    ----------
    cases : KthCases
    config : MatchConfig
    m_values : sequence of float, optional
        Fixed thresholds; None runs the config's own m (e.g. 'auto') once.
    legacy : bool or str
        Scoring mode of ``score_matches``.

    Returns
    -------
    dict
        ``{annotator: {sketch: [F1 per m]}}`` (a list of one value when ``m_values`` is None),
        plus key ``"m"`` with the m values actually used per sketch.
    """
    from ursim_core.matching import match_prepared, prepare

    table = {annotator: {} for annotator in cases.references}
    used_m = {}
    for name, sketch in cases.sketches.items():
        prepared = prepare(sketch, cases.model, config)
        if prepared_hook is not None:
            prepared_hook(name, prepared)
        results = [match_prepared(prepared)] if m_values is None else [match_prepared(prepared, m) for m in m_values]
        used_m[name] = [r.m for r in results]
        for annotator in cases.references:
            reference = cases.reference(annotator, name)
            table[annotator][name] = [score_pairs(r.pairs, reference, legacy=legacy).f1 for r in results]
    table["m"] = used_m
    return table


def summarise(table: dict) -> dict:
    """Mean and median F1 per annotator for: each m column, the best fixed m and the oracle m.

    Returns
    -------
    dict
        ``{annotator: {"per_m_mean": [...], "best_fixed": (index, mean, median),
        "oracle": (mean, median), "first": (mean, median)}}`` and ``"both"`` with the means
        of the two annotators for the same entries.
    """
    summary = {}
    annotators = [a for a in table if a != "m"]
    for annotator in annotators:
        rows = np.array(list(table[annotator].values()), dtype=np.float64)
        per_m_mean = rows.mean(axis=0)
        per_m_median = np.median(rows, axis=0)
        best = int(np.argmax(per_m_mean))
        oracle = rows.max(axis=1)
        summary[annotator] = {
            "per_m_mean": per_m_mean.tolist(),
            "per_m_median": per_m_median.tolist(),
            "best_fixed": (best, float(per_m_mean[best]), float(per_m_median[best])),
            "oracle": (float(oracle.mean()), float(statistics.median(oracle.tolist()))),
            "first": (float(rows[:, 0].mean()), float(np.median(rows[:, 0]))),
        }
    summary["both"] = {
        key: float(np.mean([summary[a][key][0] if key != "best_fixed" else summary[a][key][1] for a in annotators]))
        for key in ("oracle", "first", "best_fixed")
    }
    return summary


def accuracy_report(dataset_root=None) -> dict:
    """Print the accuracy figures quoted in ``ursim_core.matching.auto_m`` from the current code.

    Rows: the paper's method, the released options (on the recommended pipeline and, with
    fnfix scoring, on the released pipeline: the faithfulness check), ablations of the default and
    the default itself; columns: oracle m, best fixed m, automatic m (mean F1 per annotator).

    Returns
    -------
    dict
        label -> summary (see :func:`summarise`), for the rows that ran.
    """
    from dataclasses import replace

    from ursim_core.evaluation.datasets import dataset_root as locate
    from ursim_core.matching import M_GRID, MatchConfig

    root = locate(dataset_root)
    if root is None:
        print("accuracy_report: datasets not found, skipped")
        return {}
    rows = [
        ("paper", "recommended", MatchConfig.paper(), True, True, False),
        ("released options", "recommended", MatchConfig.released(), True, False, False),
        ("released options, released pipeline, fnfix", "released", MatchConfig.released(), True, False, "fnfix"),
        ("default, structure score", "recommended", MatchConfig(hypothesis_score="structure"), False, True, False),
        ("default, no position", "recommended", MatchConfig(position_weight=0.0), False, True, False),
        ("default", "recommended", MatchConfig(), True, True, False),
    ]
    summaries = {}
    for label, pipeline, config, with_grid, with_auto, legacy in rows:
        cases = kth_pairs(root, pipeline=pipeline)
        parts = [label]
        if with_grid:
            s = summarise(f1_table(cases, config, M_GRID, legacy=legacy))
            summaries[label] = s
            parts.append("oracle " + " / ".join(f"{s[a]['oracle'][0]:.3f}" for a in ANNOTATORS))
            parts.append(
                "best fixed "
                + " / ".join(f"{s[a]['best_fixed'][1]:.3f} (m {M_GRID[s[a]['best_fixed'][0]]})" for a in ANNOTATORS)
            )
        if with_auto:
            s = summarise(f1_table(cases, replace(config, m="auto"), legacy=legacy))
            summaries[label + ", auto"] = s
            parts.append(
                "auto " + " / ".join(f"{s[a]['first'][0]:.3f} (median {s[a]['first'][1]:.3f})" for a in ANNOTATORS)
            )
        print(" | ".join(parts), flush=True)
    return summaries
