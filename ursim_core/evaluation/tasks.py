"""The scored work of an evaluation: ground truth per segmentation, match tasks, human vs human.

An :class:`Instance` is one experiment in one orientation of its sketch (upright unless the
evaluation is augmented); the ground-truth sketch points of a turned sketch are turned with it.

1. The ground-truth points of each annotator are mapped to the regions of the segmentations being
   evaluated (:func:`ursim_core.correspondences.assign_regions`, 10 px tolerance as the released
   code). The points were clicked on MAORIS with its default parameters; they are mapped onto
   whatever segmentation is evaluated, so a point may land in a merged or split region.
2. For each (experiment, matcher, variant) the m-independent work is done once
   (:func:`ursim_core.matching.prepare`), then every m of the grid and ``m="auto"`` are matched
   (:func:`ursim_core.matching.match_prepared`) and scored against every annotator. These tasks
   run on the process pool, the segmentations handed to each worker once.
   Each run is also scored by place accuracy
   (:func:`ursim_core.evaluation.place.place_accuracy`) against a fixed reference segmentation
   of the metric map (MAORIS ``default``, the one the annotators clicked on).
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

from ursim_core.evaluation.cache import SegmentationJob
from ursim_core.evaluation.layouts import Experiment
from ursim_core.evaluation.place import place_problem, score_places
from ursim_core.evaluation.pool import Progress, completed
from ursim_core.evaluation.results import AUTO, CEILING, HUMAN, RunRow, m_label
from ursim_core.evaluation.scoring import score_cliques, score_matches

__all__ = [
    "Instance",
    "Reference",
    "MatchTask",
    "model_label",
    "references_of",
    "run_task",
    "run_tasks",
    "sorted_rows",
    "human_vs_human_rows",
    "ceiling_rows",
]


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


@dataclass(frozen=True)
class Instance:
    """One experiment with its sketch in one orientation, and the segmentation jobs it needs.

    ``upright_job`` is the sketch as it is (its shape is the frame of the ground-truth points);
    ``place_job`` the fixed reference segmentation of the metric map for place accuracy.
    """

    experiment: Experiment
    sketch_job: SegmentationJob
    metric_job: SegmentationJob
    place_job: SegmentationJob
    upright_job: SegmentationJob
    orientation: Any = None
    augment: str = ""

    @property
    def jobs(self) -> tuple[SegmentationJob, ...]:
        return (self.sketch_job, self.metric_job, self.place_job, self.upright_job)


@dataclass(frozen=True)
class Reference:
    """One annotator's ground truth on one instance: region cliques (in the evaluated
    segmentations) for pair scores, point cliques (in the instance's frame) for place accuracy."""

    regions: tuple
    points: tuple


def references_of(instances: list[Instance], segmentations) -> tuple[list[dict[str, Reference]], list[str]]:
    """Per instance (same order): annotator -> :class:`Reference`; and notes on dropped points."""
    from ursim_core.correspondences import assign_regions, load_dat, regions_at_points
    from ursim_core.evaluation.augment import transform_correspondences

    loaded: dict[Path, Any] = {}
    references: list[dict[str, Reference]] = []
    notes: list[str] = []
    for instance in instances:
        experiment = instance.experiment
        # Read once: a turned sketch's labels are unpacked at each read (evaluation.packing).
        sketch_labels = segmentations[instance.sketch_job.key].labels
        metric_labels = segmentations[instance.metric_job.key].labels
        per_annotator = {}
        for annotator, gt_path in experiment.ground_truth.items():
            if gt_path not in loaded:
                loaded[gt_path] = load_dat(gt_path)
            corr = loaded[gt_path]
            if instance.orientation is not None:
                shape = segmentations[instance.upright_job.key].labels.shape
                corr = transform_correspondences(corr, shape, instance.orientation)
            assigned = assign_regions(corr, sketch_labels, metric_labels, tolerance=10)
            per_annotator[annotator] = Reference(
                regions=tuple((tuple(c.sketch_regions), tuple(c.metric_regions)) for c in assigned.cliques),
                points=tuple((tuple(c.sketch_points), tuple(c.metric_points)) for c in corr.cliques),
            )
            dropped = sum(
                regions_at_points(labels, points, tolerance=10).count(0)
                for labels, points in (
                    (sketch_labels, [p for c in corr.cliques for p in c.sketch_points]),
                    (metric_labels, [p for c in corr.cliques for p in c.metric_points]),
                )
            )
            if dropped:
                where = f"{experiment.name} {instance.augment}" if instance.augment else experiment.name
                notes.append(
                    f"{where} ({annotator}): {dropped} ground-truth point(s) more than 10 px from any region, dropped"
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
    place_key: str
    matcher: str
    variant: str
    config: Any
    m_grid: tuple
    references: dict
    legacy: str
    auto_m: bool
    augment: str = ""

    @property
    def order_key(self) -> tuple:
        return (self.name, self.augment, self.model, self.matcher, self.variant)


#: Segmentations of a worker process (and the packed resamplings of some), handed over once by
#: the pool initializer.
_WORKER_SEGMENTATIONS: dict[str, Any] = {}
_WORKER_PACKED: dict[str, Any] = {}


def _init_worker(segmentations: dict[str, Any], packed: dict[str, Any] | None = None) -> None:
    global _WORKER_SEGMENTATIONS, _WORKER_PACKED
    _WORKER_SEGMENTATIONS, _WORKER_PACKED = segmentations, packed or {}


def _run_task_in_worker(task: MatchTask) -> list[RunRow]:
    return run_task(task, _WORKER_SEGMENTATIONS, _WORKER_PACKED)


def run_task(task: MatchTask, segmentations: dict[str, Any], packed: dict[str, Any] | None = None) -> list[RunRow]:
    """Prepare once, match at every m (and auto), score against every annotator.

    ``packed``: resamplings packed apart from their segmentations by job key
    (:func:`ursim_core.evaluation.cache.segment_all`), unpacked here for the sketch's vote.
    """
    from ursim_core.evaluation.packing import with_unpacked
    from ursim_core.matching import match_prepared, prepare

    sketch_seg = with_unpacked(segmentations[task.sketch_key], (packed or {}).get(task.sketch_key))
    metric_seg = segmentations[task.metric_key]
    place_labels = segmentations[task.place_key].labels
    # What place accuracy needs of each annotator's ground truth does not depend on m.
    problems = {
        annotator: place_problem(reference.points, sketch_seg.labels, place_labels)
        for annotator, reference in task.references.items()
    }
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
            score = score_matches(result.pairs, reference.regions, legacy=task.legacy)
            place = score_places(result.pairs, problems[annotator], metric_seg.graph)
            rows.append(
                RunRow(
                    map=task.name,
                    annotator=annotator,
                    matcher=task.matcher,
                    variant=task.variant,
                    m_label=label,
                    m_value=float(result.m),
                    **_score_fields(score),
                    seeds=int(result.seeds_count),
                    n_sketch_regions=sketch_seg.n_regions,
                    n_metric_regions=metric_seg.n_regions,
                    time_s=elapsed,
                    model=task.model,
                    n_pairs=len(result.pairs),
                    scoring=score.mode,
                    reason=result.reason,
                    place_accuracy=place.accuracy,
                    augment=task.augment,
                )
            )
    return rows


def run_tasks(
    tasks: list[MatchTask],
    segmentations: dict[str, Any],
    workers: int,
    reporter: Progress,
    packed: dict[str, Any] | None = None,
) -> list[RunRow]:
    # Largest problems first so the workers finish together; the segmentations reach each
    # worker once through the pool initializer instead of once per task.
    order = sorted(
        tasks, key=lambda t: -(segmentations[t.sketch_key].n_regions * segmentations[t.metric_key].n_regions)
    )
    if workers <= 1 or len(order) < 2:
        finished = completed(functools.partial(run_task, segmentations=segmentations, packed=packed), order, workers=1)
    else:
        finished = completed(
            _run_task_in_worker, order, workers=workers, initializer=_init_worker, initargs=(segmentations, packed)
        )
    rows: list[RunRow] = []
    for task, task_rows in finished:
        rows.extend(task_rows)
        turned = f" {task.augment}" if task.augment else ""
        reporter.step(f"match {task.name}{turned} {task.matcher} {task.variant}")
    return sorted_rows(tasks, rows)


def sorted_rows(tasks: list[MatchTask], rows: list[RunRow]) -> list[RunRow]:
    """Rows in task order, then annotator, then m in grid order (auto last): any run order gives one CSV."""
    position = {task.order_key: index for index, task in enumerate(tasks)}
    m_position = {label: i for i, label in enumerate([m_label(m) for m in tasks[0].m_grid] + [AUTO])} if tasks else {}
    rows.sort(
        key=lambda r: (
            position[(r.map, r.augment, r.model, r.matcher, r.variant)],
            r.annotator,
            m_position.get(r.m_label, 0),
        )
    )
    return rows


# --------------------------------------------------------------------------- human vs human


def human_vs_human_rows(instances: list[Instance], segmentations, references, legacy_mode) -> list[RunRow]:
    """Each annotator's cliques scored against each other's, by pairs and by place accuracy.

    For place accuracy the scored annotator's cliques act as the matches: every pair of a
    sketch region and a metric region of one clique.
    """
    rows = []
    for instance, per_annotator in zip(instances, references):
        if len(per_annotator) < 2:
            continue
        sketch_seg = segmentations[instance.sketch_job.key]
        metric_seg = segmentations[instance.metric_job.key]
        place_labels = segmentations[instance.place_job.key].labels
        for reference_annotator, reference in per_annotator.items():
            problem = place_problem(reference.points, sketch_seg.labels, place_labels)
            for scored_annotator, scored in per_annotator.items():
                if scored_annotator == reference_annotator:
                    continue
                score = score_cliques(scored.regions, reference.regions, legacy=legacy_mode)
                place = score_places(score.pairs, problem, metric_seg.graph)
                rows.append(
                    _unmatched_row(
                        instance, sketch_seg, metric_seg, reference_annotator, HUMAN, scored_annotator, score, place
                    )
                )
    return rows


# --------------------------------------------------------------------------- ceiling


def ceiling_rows(instances: list[Instance], segmentations, references, legacy_mode) -> list[RunRow]:
    """The best one-to-one answer against every annotator at once, scored against each
    (:mod:`ursim_core.evaluation.ceiling`): what any one-to-one matcher can reach at most.

    Correct scoring only (the legacy scorers count pairs per clique): none in a legacy mode.
    ``variant`` says whether the search was exhaustive (``'one-to-one'``) or stopped at its node
    budget (``'one-to-one, lower bound'``).
    """
    from ursim_core.evaluation.ceiling import best_one_to_one

    if legacy_mode != "correct":
        return []
    rows = []
    for instance, per_annotator in zip(instances, references):
        if not per_annotator:
            continue
        sketch_seg = segmentations[instance.sketch_job.key]
        metric_seg = segmentations[instance.metric_job.key]
        place_labels = segmentations[instance.place_job.key].labels
        ceiling = best_one_to_one([reference.regions for reference in per_annotator.values()])
        variant = "one-to-one" if ceiling.exact else "one-to-one, lower bound"
        for annotator, reference in per_annotator.items():
            score = score_matches(ceiling.pairs, reference.regions)
            problem = place_problem(reference.points, sketch_seg.labels, place_labels)
            place = score_places(ceiling.pairs, problem, metric_seg.graph)
            rows.append(_unmatched_row(instance, sketch_seg, metric_seg, annotator, CEILING, variant, score, place))
    return rows


def _unmatched_row(instance: Instance, sketch_seg, metric_seg, annotator, matcher, variant, score, place) -> RunRow:
    """The row of pairs no matcher made (an annotator's, the ceiling's): no m, seeds or time."""
    return RunRow(
        map=instance.experiment.name,
        annotator=annotator,
        matcher=matcher,
        variant=variant,
        m_label="-",
        m_value=math.nan,
        **_score_fields(score),
        seeds=0,
        n_sketch_regions=sketch_seg.n_regions,
        n_metric_regions=metric_seg.n_regions,
        time_s=0.0,
        model=model_label(instance.experiment),
        n_pairs=len(score.pairs),
        scoring=score.mode,
        place_accuracy=place.accuracy,
        augment=instance.augment,
    )


def _score_fields(score) -> dict:
    """The RunRow fields of a :class:`~ursim_core.evaluation.scoring.MatchScore`."""
    return {name: getattr(score, name) for name in ("tp", "fp", "fn", "precision", "recall", "f1")}
