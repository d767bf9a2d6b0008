"""The scored work of an evaluation: ground truth per segmentation, match tasks, human vs human.

1. The ground-truth points of each annotator are mapped to the regions of the segmentations being
   evaluated (:func:`ursim_core.correspondences.codec.assign_regions`, 10 px tolerance as the released
   code). The points were clicked on MAORIS with its default parameters; they are mapped onto
   whatever segmentation is evaluated, so a point may land in a merged or split region.
2. For each (experiment, matcher, variant) the m-independent work is done once
   (:func:`ursim_core.matching.prepare`), then every m of the grid and ``m="auto"`` are matched
   (:func:`ursim_core.matching.match_prepared`) and scored against every annotator. These tasks
   run on the process pool, the segmentations handed to each worker once.
3. Human vs human: on a map pair that several annotators annotated, each annotator's cliques are
   scored against each other's (:func:`ursim_core.evaluation.scoring.score_cliques`).
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ursim_core.evaluation.layouts import Experiment
from ursim_core.evaluation.pool import Progress, completed
from ursim_core.evaluation.results import AUTO, HUMAN, RunRow, m_label
from ursim_core.evaluation.scoring import score_cliques, score_matches

__all__ = ["MatchTask", "model_label", "references_of", "run_tasks", "human_vs_human_rows"]


def model_label(experiment: Experiment) -> str:
    """The model map as a path inside the dataset without suffix (``model/model_simple``,
    ``GT/Malcolm/model_simple``): unique where the file names are not."""
    metric = Path(experiment.metric)
    if experiment.dataset is not None:
        try:
            return metric.relative_to(experiment.dataset).with_suffix("").as_posix()
        except ValueError:
            pass
    return metric.stem


def references_of(experiments, input_jobs, segmentations):
    """Per experiment (same order): annotator -> reference cliques as (sketch_regions, metric_regions)."""
    from ursim_core.correspondences.codec import assign_regions, load_dat, regions_at_points

    references: list[dict[str, tuple]] = []
    notes: list[str] = []
    for experiment, (sketch_job, metric_job) in zip(experiments, input_jobs):
        sketch_seg = segmentations[sketch_job.key]
        metric_seg = segmentations[metric_job.key]
        per_annotator = {}
        for annotator, gt_path in experiment.ground_truth.items():
            corr = load_dat(gt_path)
            assigned = assign_regions(corr, sketch_seg.labels, metric_seg.labels, tolerance=10)
            per_annotator[annotator] = tuple(
                (tuple(c.sketch_regions), tuple(c.metric_regions)) for c in assigned.cliques
            )
            dropped = sum(
                regions_at_points(labels, points, tolerance=10).count(0)
                for labels, points in (
                    (sketch_seg.labels, [p for c in corr.cliques for p in c.sketch_points]),
                    (metric_seg.labels, [p for c in corr.cliques for p in c.metric_points]),
                )
            )
            if dropped:
                notes.append(
                    f"{experiment.name} ({annotator}): {dropped} ground-truth point(s) more than 10 px from any region, dropped"
                )
        references.append(per_annotator)
    return references, notes


# --------------------------------------------------------------------------- matching tasks


@dataclass(frozen=True)
class MatchTask:
    name: str
    model: str
    sketch_key: str
    metric_key: str
    matcher: str
    variant: str
    config: Any
    m_grid: tuple
    references: dict
    legacy: str
    auto_m: bool


#: Segmentations of a worker process, handed over once by the pool initializer.
_WORKER_SEGMENTATIONS: dict[str, Any] = {}


def _init_worker(segmentations: dict[str, Any]) -> None:
    global _WORKER_SEGMENTATIONS
    _WORKER_SEGMENTATIONS = segmentations


def _run_task_in_worker(task: MatchTask) -> list[RunRow]:
    return _run_task(task, _WORKER_SEGMENTATIONS)


def _run_task(task: MatchTask, segmentations: dict[str, Any]) -> list[RunRow]:
    """Prepare once, match at every m (and auto), score against every annotator."""
    from ursim_core.matching import match_prepared, prepare

    sketch_seg = segmentations[task.sketch_key]
    metric_seg = segmentations[task.metric_key]
    prepared = prepare(sketch_seg, metric_seg, task.config)
    runs = [(m_label(m), m) for m in task.m_grid]
    if task.auto_m:
        runs.append((AUTO, None))
    rows = []
    for label, m in runs:
        started = time.perf_counter()
        result = match_prepared(prepared, m)
        elapsed = time.perf_counter() - started
        for annotator, reference in task.references.items():
            score = score_matches(result.pairs, reference, legacy=task.legacy)
            rows.append(
                RunRow(
                    map=task.name,
                    annotator=annotator,
                    matcher=task.matcher,
                    variant=task.variant,
                    m_label=label,
                    m_value=float(result.m),
                    tp=score.tp,
                    fp=score.fp,
                    fn=score.fn,
                    precision=score.precision,
                    recall=score.recall,
                    f1=score.f1,
                    seeds=int(result.seeds_count),
                    n_sketch_regions=sketch_seg.n_regions,
                    n_metric_regions=metric_seg.n_regions,
                    time_s=elapsed,
                    model=task.model,
                    n_pairs=len(result.pairs),
                    scoring=score.mode,
                    reason=result.reason,
                )
            )
    return rows


def run_tasks(tasks: list[MatchTask], segmentations: dict[str, Any], workers: int, reporter: Progress) -> list[RunRow]:
    # Largest problems first so the workers finish together; the segmentations reach each
    # worker once through the pool initializer instead of once per task.
    order = sorted(
        tasks, key=lambda t: -(segmentations[t.sketch_key].n_regions * segmentations[t.metric_key].n_regions)
    )
    if workers <= 1 or len(order) < 2:
        finished = completed(functools.partial(_run_task, segmentations=segmentations), order, workers=1)
    else:
        finished = completed(
            _run_task_in_worker, order, workers=workers, initializer=_init_worker, initargs=(segmentations,)
        )
    rows: list[RunRow] = []
    for task, task_rows in finished:
        rows.extend(task_rows)
        reporter.step(f"match {task.name} {task.matcher} {task.variant}")
    position = {(t.name, t.model, t.matcher, t.variant): index for index, t in enumerate(tasks)}
    m_position = {label: i for i, label in enumerate([m_label(m) for m in tasks[0].m_grid] + [AUTO])} if tasks else {}
    rows.sort(
        key=lambda r: (position[(r.map, r.model, r.matcher, r.variant)], r.annotator, m_position.get(r.m_label, 0))
    )
    return rows


# --------------------------------------------------------------------------- human vs human


def human_vs_human_rows(experiments, input_jobs, segmentations, references, legacy_mode) -> list[RunRow]:
    rows = []
    for experiment, (sketch_job, metric_job), per_annotator in zip(experiments, input_jobs, references):
        if len(per_annotator) < 2:
            continue
        sketch_seg = segmentations[sketch_job.key]
        metric_seg = segmentations[metric_job.key]
        for reference_annotator, reference in per_annotator.items():
            for scored_annotator, scored in per_annotator.items():
                if scored_annotator == reference_annotator:
                    continue
                score = score_cliques(scored, reference, legacy=legacy_mode)
                rows.append(
                    RunRow(
                        map=experiment.name,
                        annotator=reference_annotator,
                        matcher=HUMAN,
                        variant=scored_annotator,
                        m_label="-",
                        m_value=math.nan,
                        tp=score.tp,
                        fp=score.fp,
                        fn=score.fn,
                        precision=score.precision,
                        recall=score.recall,
                        f1=score.f1,
                        seeds=0,
                        n_sketch_regions=sketch_seg.n_regions,
                        n_metric_regions=metric_seg.n_regions,
                        time_s=0.0,
                        model=model_label(experiment),
                        n_pairs=len(score.pairs),
                        scoring=score.mode,
                    )
                )
    return rows
