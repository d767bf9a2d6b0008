"""The experiment runner behind ``ursim evaluate``: every matcher and variant, m swept, both annotators.

Pipeline (:func:`run_evaluation`):

1. :func:`ursim_core.evaluation.layouts.discover` lists the experiments (map pair + ground truth).
2. Every distinct map is loaded and segmented once, in parallel over ``workers`` processes
   (biggest maps first so the two cores finish together). Segmentations can be kept across runs
   in a caller-owned dict (``segmentation_cache``) and on disk (``cache_dir``); keys include the
   file's SHA-256, so an edited map is segmented again.
3. The ground-truth points of each annotator are mapped to the regions of the segmentations being
   evaluated (:func:`ursim_core.correspondences.assign_regions`, 10 px tolerance as the released
   code). The points were clicked on MAORIS with its default parameters; they are mapped onto
   whatever segmentation is evaluated, so a point may land in a merged or split region.
4. For each (experiment, matcher, variant) the m-independent work is done once, then every m of
   the grid and ``m="auto"`` are matched and scored against every annotator
   (:mod:`~ursim_core.evaluation.tasks`, on the process pool of :mod:`~ursim_core.evaluation.pool`).
5. Human vs human: on a map pair that several annotators annotated, each annotator's cliques are
   scored against each other's.

Summaries (:func:`summarise`): for each annotator (and all annotators pooled) and each matcher x

Summaries are computed by :mod:`~ursim_core.evaluation.results`; the segmentation jobs and their
caches live in :mod:`~ursim_core.evaluation.cache`; :mod:`~ursim_core.evaluation.report` turns a
result into tables, a CSV, plots and a markdown summary.

Scoring is correct by default; ``legacy_scoring=True`` reproduces what the released binary printed
(false negatives always 0) and ``"fnfix"`` the released scorer with its uninitialised flag fixed
(see :mod:`ursim_core.evaluation.scoring`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import os
import time
from collections.abc import MutableMapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.evaluation.augment import UPRIGHT, Orientation, parse_augment
from ursim_core.evaluation.cache import SegmentationJob, segment_all
from ursim_core.evaluation.layouts import Experiment, discover
from ursim_core.evaluation.place import PLACE_REFERENCE_PRESET
from ursim_core.evaluation.pool import Progress, ProgressCallback
from ursim_core.evaluation.results import (
    AUTO,
    DEFAULT_M_GRID,
    DEFAULT_MATCHERS,
    MATCHERS,
    POOLED,
    VARIANTS,
    EvaluationResult,
    RunRow,
    Summary,
    m_label,
    mean_f1_by_m,
    summarise,
    summarise_human,
)
from ursim_core.evaluation.scoring import score_matches
from ursim_core.evaluation.tasks import (
    Instance,
    MatchTask,
    ceiling_rows,
    human_vs_human_rows,
    model_label,
    references_of,
    run_tasks,
)

__all__ = [
    "run_evaluation",
    # Re-exported: the values of a result, from their own module.
    "DEFAULT_M_GRID",
    "MATCHERS",
    "VARIANTS",
    "POOLED",
    "RunRow",
    "Summary",
    "EvaluationResult",
    "m_label",
    "summarise",
    "summarise_human",
    "mean_f1_by_m",
]


def run_evaluation(
    dataset_dir: str | Path | Sequence[Experiment],
    *,
    matchers: Sequence[str] = DEFAULT_MATCHERS,
    variants: Sequence[str] = VARIANTS,
    m_grid: Sequence[float] = DEFAULT_M_GRID,
    preset: str | None = None,
    metric_preset: str | None = None,
    legacy_scoring: bool | str = False,
    workers: int = 2,
    progress: ProgressCallback | None = None,
    config_overrides: dict[str, Any] | None = None,
    released: bool = False,
    maps: Sequence[str] | None = None,
    auto_m: bool = True,
    human: bool = True,
    segmentation_cache: MutableMapping | None = None,
    cache_dir: str | Path | None = None,
    threshold: float | None = None,
    nonzero_free: bool | None = None,
    augment: str | Sequence[Orientation] | None = None,
    scheduler: Any = None,
) -> EvaluationResult:
    """Run every matcher x variant over a dataset, sweeping m, and score against every annotator.

    Parameters
    ----------
    dataset_dir : str, Path or sequence of Experiment
        A dataset folder (see :func:`ursim_core.evaluation.layouts.discover`) or experiments.
    matchers : sequence of {'planar', 'hungarian', 'vf2'}, keyword-only
    variants : sequence of {'baseline', 'T1', 'T2', 'T3', 'T4'}, keyword-only
    m_grid : sequence of float, keyword-only
        Fixed values of m to run; also the grid the automatic m chooses from.
    preset : str, keyword-only
        MAORIS preset of the input maps (sketches or robot maps). Default:
        ``ursim_core.matching.MATCH_PRESETS`` (``'ursim-released'`` when ``released``).
    metric_preset : str, keyword-only
        MAORIS preset of the model map. Default: ``ursim_core.matching.MATCH_PRESETS``
        (``'ursim-released'`` when ``released``).
    legacy_scoring : {False, True, 'fnfix'}, keyword-only
        False: correct scoring. True: the released binary's (FN always 0). 'fnfix': the released
        scorer with its flag fixed.
    workers : int, keyword-only
        Processes for segmentation and matching; 1 (or 0) runs everything in this process.
    progress : callable, keyword-only
        ``progress(done, total, text)``, called from this process after each step.
    config_overrides : dict, keyword-only
        :class:`~ursim_core.matching.MatchConfig` fields replaced in every run (``variant``,
        ``matcher`` and ``m`` are set by the runner).
    released : bool, keyword-only
        Reproduce the released driver: :meth:`MatchConfig.released` (uniqueness weights for T4,
        the variant's own weights otherwise), the ``'ursim-released'`` segmentation preset for
        both maps and every non-zero pixel free.
    maps : sequence of str, keyword-only
        Only run the experiments whose map name is listed.
    auto_m : bool, keyword-only
        Also run ``m='auto'``.
    human : bool, keyword-only
        Also score annotators against each other.
    segmentation_cache : mutable mapping, keyword-only
        Caller-owned cache of segmentations, reused across calls.
    cache_dir : str or Path, keyword-only
        Folder of an on-disk segmentation cache (created if needed).
    threshold, nonzero_free : keyword-only
        Map loading options (:func:`ursim_core.io.maps.load_map`); default 250 / False, or
        non-zero-is-free when ``released``.
    augment : str or sequence of Orientation, keyword-only
        Score every sketch in several orientations, each as its own run (``RunRow.augment``):
        ``'dihedral'`` (the 8 orientations), ``'angles=15,30,...'`` or
        :class:`~ursim_core.evaluation.augment.Orientation` values. The sketch image is turned
        and mirrored (new pixels are obstacle) and its ground-truth points moved alike. The
        upright orientation is always run. None (default): the sketches as they are, with an
        empty ``augment``.

    scheduler : str or distributed.Client, keyword-only
        Run the segmentations and match tasks on this Dask cluster (a scheduler address such
        as ``'tcp://host:8786'``, or a Client) instead of ``workers`` local processes: each map
        is segmented once and the tasks take the results (:mod:`ursim_core.evaluation.distributed`;
        needs the ``distributed`` extra). The rows are the same as a local run's.

    Every run is scored by pair F1 and by place accuracy
    (:func:`ursim_core.evaluation.place.place_accuracy`), against a reference segmentation of
    each metric map with the MAORIS ``default`` preset and default loading.

    Returns
    -------
    EvaluationResult

    Raises
    ------
    ParameterError
        Unknown matcher, variant or preset, an empty selection, a bad m grid.
    FormatError, MapError
        A bad dataset folder, ground-truth file or map (the message names the file).

    Examples
    --------
    >>> from ursim_core.evaluation.datasets import dataset_root
    >>> root = dataset_root()
    >>> if root is not None:  # doctest: +SKIP
    ...     result = run_evaluation(root / "ursim_kth_sketches", matchers=["planar"], variants=["T4"], maps=["01"])
    ...     print(result.summary("malcolm", "planar", "T4", "oracle").mean)
    """
    from ursim_core.matching import MATCH_PRESETS, MatchConfig
    from ursim_core.segmentation import resolve_params

    started = time.perf_counter()
    matchers = _checked_choice(matchers, MATCHERS, "matchers")
    variants = _checked_choice(variants, VARIANTS, "variants")
    m_grid = _checked_grid(m_grid)
    legacy_mode = _scoring_mode(legacy_scoring)
    workers = max(1, int(workers))

    if isinstance(dataset_dir, (str, os.PathLike)):
        dataset = Path(dataset_dir)
        experiments = discover(dataset)
    else:
        experiments = list(dataset_dir)
        dataset = experiments[0].dataset if experiments else None
    if maps is not None:
        wanted = {str(name) for name in maps}
        unknown = wanted - {e.name for e in experiments}
        if unknown:
            raise ParameterError(
                f"no experiment for map(s) {', '.join(sorted(unknown))}; available: {', '.join(dict.fromkeys(e.name for e in experiments))}",
                field="maps",
            )
        experiments = [e for e in experiments if e.name in wanted]
    if not experiments:
        raise ParameterError("no experiment to run (no map with ground truth)", path=dataset)

    base_config = MatchConfig.released() if released else MatchConfig()
    overrides = dict(config_overrides or {})
    known = {f.name for f in dataclasses.fields(MatchConfig)}
    for name in overrides:
        if name in ("variant", "matcher", "m", "m_grid"):
            raise ParameterError(
                f"'{name}' is set by the runner; use the matchers/variants/m_grid options", field="config_overrides"
            )
        if name not in known:
            raise ParameterError(
                f"unknown matching option '{name}' (known: {', '.join(sorted(known))})", field="config_overrides"
            )
    base_config = dataclasses.replace(base_config, m_grid=tuple(m_grid), **overrides)

    load_options = {
        "threshold": 250 if threshold is None else threshold,
        "nonzero_free": released if nonzero_free is None else bool(nonzero_free),
    }
    orientations = _checked_orientations(augment)
    input_preset = preset or ("ursim-released" if released else MATCH_PRESETS["sketch"])
    model_preset = metric_preset or ("ursim-released" if released else MATCH_PRESETS["metric"])
    # Per experiment and orientation: the segmentation jobs of the instance.
    instances: list[Instance] = []
    digests: dict[Path, str] = {}
    # A sketch whose orientation the matcher does not assume is segmented in its canonical pose.
    canonical = base_config.orientation != "upright"
    for experiment in experiments:
        # The planar matcher votes over the other resamplings of a sketch resampled onto its axes.
        resampled = (
            canonical
            and base_config.resampling_vote
            and any(
                _config_for(base_config, matcher, variant, released, experiment.input_kind).resolved().matcher
                == "planar"
                for matcher in matchers
                for variant in variants
            )
        )
        upright = SegmentationJob.of(
            experiment.sketch, input_preset, load_options, digests, canonical=canonical, resampled=resampled
        )
        metric_job = SegmentationJob.of(experiment.metric, model_preset, load_options, digests)
        place_job = SegmentationJob.of(experiment.metric, PLACE_REFERENCE_PRESET, PLACE_REFERENCE_LOAD, digests)
        for orientation in orientations or (None,):
            instances.append(
                Instance(
                    experiment=experiment,
                    sketch_job=SegmentationJob.of(
                        experiment.sketch,
                        input_preset,
                        load_options,
                        digests,
                        orientation,
                        canonical=canonical,
                        resampled=resampled,
                    ),
                    metric_job=metric_job,
                    place_job=place_job,
                    upright_job=upright,
                    orientation=None if orientation is None or orientation.is_identity else orientation,
                    augment="" if orientation is None else orientation.name,
                )
            )
    distinct_jobs = list(dict.fromkeys(job for instance in instances for job in instance.jobs))
    for preset_name in sorted({job.preset for job in distinct_jobs}):
        # An unknown preset is reported now, not by a worker process after other maps ran.
        resolve_params("maoris", preset_name)

    n_tasks = len(instances) * len(matchers) * len(variants)
    total_steps = len(distinct_jobs) + n_tasks + (1 if human else 0)
    reporter = Progress(progress, total_steps)

    with contextlib.ExitStack() as stack:
        # A client made here from an address is closed here, even on an error.
        client = None
        if scheduler is not None:
            from ursim_core.evaluation.distributed import connect, run_tasks_dask, segment_all_dask

            client = connect(scheduler)
            if client is not scheduler:
                stack.callback(client.close)
        segment_started = time.perf_counter()
        # The resamplings of turned sketches are kept packed until a task needs them.
        packed: dict = {}
        if client is None:
            segmentations, cached = segment_all(
                distinct_jobs, workers, reporter, segmentation_cache, cache_dir, packed=packed
            )
        else:
            segmentations, futures, cached = segment_all_dask(
                client, distinct_jobs, reporter, segmentation_cache, cache_dir
            )
        segmentation_s = time.perf_counter() - segment_started

        references, notes = references_of(instances, segmentations)
        warnings = _missing_annotator_warnings(experiments)
        match_started = time.perf_counter()
        tasks = [
            MatchTask(
                name=instance.experiment.name,
                model=model_label(instance.experiment),
                sketch_key=instance.sketch_job.key,
                metric_key=instance.metric_job.key,
                place_key=instance.place_job.key,
                matcher=matcher,
                variant=variant,
                config=_config_for(base_config, matcher, variant, released, instance.experiment.input_kind),
                m_grid=tuple(m_grid),
                references=reference,
                legacy=legacy_mode,
                auto_m=auto_m,
                augment=instance.augment,
            )
            for instance, reference in zip(instances, references)
            for matcher in matchers
            for variant in variants
        ]
        if client is None:
            rows = run_tasks(tasks, segmentations, workers, reporter, packed)
        else:
            rows = run_tasks_dask(client, tasks, futures, reporter)
    matching_s = time.perf_counter() - match_started

    human_rows: list[RunRow] = []
    if human:
        human_rows = human_vs_human_rows(instances, segmentations, references, legacy_mode)
        reporter.step("human vs human")
    ceilings = ceiling_rows(instances, segmentations, references, legacy_mode)

    settings = {
        "dataset": None if dataset is None else str(dataset),
        "matchers": list(matchers),
        "variants": list(variants),
        "m_grid": [float(m) for m in m_grid],
        "auto_m": auto_m,
        "preset": preset,
        "metric_preset": metric_preset,
        "presets_used": sorted({job.preset for i in instances for job in (i.sketch_job, i.metric_job)}),
        "load_options": load_options,
        "scoring": legacy_mode,
        "released": released,
        "workers": workers,
        "scheduler": None if scheduler is None else _scheduler_address(scheduler),
        "config": _config_summary(base_config),
        "config_overrides": overrides,
        "n_experiments": len(experiments),
        "augment": [o.name for o in orientations],
        "place_reference_preset": PLACE_REFERENCE_PRESET,
    }
    timings = {
        "segmentation_s": segmentation_s,
        "matching_s": matching_s,
        "total_s": time.perf_counter() - started,
        "maps": len(distinct_jobs),
        "maps_from_cache": cached,
        # Each match is scored once per annotator with the same time: count it once.
        "match_cpu_s": float(sum({(r.map, r.model, r.matcher, r.variant, r.m_label): r.time_s for r in rows}.values())),
    }
    return EvaluationResult(
        rows=tuple(rows),
        human_rows=tuple(human_rows),
        ceiling_rows=tuple(ceilings),
        experiments=tuple(experiments),
        settings=settings,
        timings=timings,
        notes=tuple(warnings + notes),
        warnings=tuple(warnings),
    )


#: Loading of the metric map for its place-accuracy reference segmentation (the default loading).
PLACE_REFERENCE_LOAD = {"threshold": 250, "nonzero_free": False}


def _checked_orientations(augment) -> tuple[Orientation, ...]:
    if augment is None:
        return ()
    orientations = parse_augment(augment) if isinstance(augment, str) else tuple(augment)
    for item in orientations:
        if not isinstance(item, Orientation):
            raise ParameterError(f"expected Orientation values, got {item!r}", field="augment")
    # Upright first, always: every augmented run has its reference orientation.
    return tuple(dict.fromkeys((UPRIGHT, *orientations)))


def _scheduler_address(scheduler) -> str:
    if isinstance(scheduler, str):
        return scheduler
    info = getattr(scheduler, "scheduler_info", None)
    return str((info() if callable(info) else {}).get("address", scheduler))


def _missing_annotator_warnings(experiments) -> list[str]:
    """Say which maps are scored against fewer annotators than the dataset has."""
    annotators = list(dict.fromkeys(name for e in experiments for name in e.ground_truth))
    warnings = []
    if len(annotators) < 2:
        return warnings
    for experiment in experiments:
        missing = [name for name in annotators if name not in experiment.ground_truth]
        if missing:
            present = ", ".join(experiment.ground_truth) or "nobody"
            warnings.append(
                f"map {experiment.name} (model {model_label(experiment)}): no ground truth of "
                f"{', '.join(missing)} (file missing); scored against {present} only"
            )
    return warnings


def _checked_choice(values: Sequence[str], allowed: Sequence[str], name: str) -> list[str]:
    values = list(dict.fromkeys(values))
    lowered = {a.lower(): a for a in allowed}
    result = []
    for value in values:
        canonical = lowered.get(str(value).lower())
        if canonical is None:
            raise ParameterError(f"unknown value {value!r}; choose from {', '.join(allowed)}", field=name)
        result.append(canonical)
    if not result:
        raise ParameterError(f"choose at least one of {', '.join(allowed)}", field=name)
    return result


def _checked_grid(m_grid: Sequence[float]) -> list[float]:
    values = []
    for m in m_grid:
        if (
            isinstance(m, bool)
            or not isinstance(m, (int, float, np.floating, np.integer))
            or not math.isfinite(m)
            or m < 0
        ):
            raise ParameterError(f"m values must be non-negative numbers, got {m!r}", field="m_grid")
        values.append(float(m))
    if not values:
        raise ParameterError("needs at least one value of m", field="m_grid")
    labels = [m_label(m) for m in values]
    if len(set(labels)) != len(labels):
        raise ParameterError("the values of m must differ", field="m_grid")
    return values


def _scoring_mode(legacy: bool | str) -> str:
    # Validated by the scorer itself, which knows its modes.
    return score_matches([], [], legacy=legacy).mode


def _config_for(base, matcher: str, variant: str, released: bool, input_kind: str = "sketch"):
    changes: dict[str, Any] = {"matcher": matcher, "variant": variant, "m": AUTO}
    if base.input_kind is None:
        # What the layout knows of its input maps (robot maps or sketches), unless told otherwise.
        changes["input_kind"] = input_kind
    if released and variant != "T4":
        # The released code set uniqueness weights for URSIM (T4); the other variants are
        # defined by their own weights (T1/T2 equal, T3 size).
        changes["weights"] = None
    return dataclasses.replace(base, **changes)


def _config_summary(config) -> dict:
    values = dataclasses.asdict(config)
    values.pop("variant", None)
    values.pop("matcher", None)
    return {key: (list(value) if isinstance(value, tuple) else value) for key, value in values.items()}
