"""The experiment runner behind ``ursim evaluate``: every matcher and variant, m swept, both annotators.

Pipeline (:func:`run_evaluation`):

1. :func:`ursim_core.evaluation.layouts.discover` lists the experiments (map pair + ground truth).
2. Every distinct map is loaded and segmented once, in parallel over ``workers`` processes
   (biggest maps first so the two cores finish together). Segmentations can be kept across runs
   in a caller-owned dict (``segmentation_cache``) and on disk (``cache_dir``); keys include the
   file's SHA-256, so an edited map is segmented again.
3. The ground-truth points of each annotator are mapped to the regions of the segmentations being
   evaluated (:func:`ursim_core.correspondences.codec.assign_regions`, 10 px tolerance as the released
   code). The points were clicked on MAORIS with its default parameters; they are mapped onto
   whatever segmentation is evaluated, so a point may land in a merged or split region.
4. For each (experiment, matcher, variant) the m-independent work is done once
   (:func:`ursim_core.matching.prepare`), then every m of the grid and ``m="auto"`` are matched
   (:func:`ursim_core.matching.match_prepared`) and scored against every annotator
   (:func:`score_matches`). These tasks also run on the process pool.
5. Human vs human: on a map pair that several annotators annotated, each annotator's cliques are
   scored against each other's (:func:`ursim_core.evaluation.scoring.score_cliques`).

Summaries (:func:`summarise`): for each annotator (and all annotators pooled) and each matcher x
variant, the F1 over maps with

- ``oracle``: the best m of the grid for each map (what the paper's Table 1 reports),
- ``fixed``: the single m of the grid with the best mean F1 over the maps,
- ``auto``: the automatic choice of m (:mod:`ursim_core.matching.auto_m`),

as median and mean +- sample sd. :mod:`ursim_core.evaluation.report` turns a result into tables, a CSV,
plots and a markdown summary.

Scoring is correct by default; ``legacy_scoring=True`` reproduces what the released binary printed
(false negatives always 0) and ``"fnfix"`` the released scorer with its uninitialised flag fixed
(see :mod:`ursim_core.evaluation.scoring`).
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import functools
import hashlib
import io
import json
import math
import os
import statistics
import time
from collections.abc import Callable, Iterable, MutableMapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.evaluation.layouts import Experiment, discover
from ursim_core.evaluation.scoring import MatchScore, score_cliques, score_matches
from ursim_core.matching import MATCH_PRESETS

__all__ = [
    "DEFAULT_M_GRID",
    "MATCHERS",
    "VARIANTS",
    "CHOICES",
    "POOLED",
    "Experiment",
    "RunRow",
    "Summary",
    "EvaluationResult",
    "MatchScore",
    "score_matches",
    "score_cliques",
    "discover",
    "run_evaluation",
    "summarise",
    "summarise_human",
    "mean_f1_by_m",
    "m_label",
    "format_tables",
    "write_report",
]

#: The released driver's sweep of m: 0, 0.025, ..., 0.475 (20 values).
DEFAULT_M_GRID: tuple[float, ...] = tuple(round(0.025 * i, 10) for i in range(20))
#: Matchers in the order of the report's rows.
MATCHERS = ("planar", "hungarian", "vf2")
#: Descriptor variants in the order of the paper's Table 1 columns.
VARIANTS = ("baseline", "T1", "T2", "T3", "T4")
#: How m is chosen in a summary.
CHOICES = ("oracle", "fixed", "auto")
#: Annotator name of the summaries that pool every annotator's (map, annotator) results.
POOLED = "all"
#: Matcher name of the human-vs-human rows.
HUMAN = "human"
AUTO = "auto"

ProgressCallback = Callable[[int, int, str], None]


def m_label(m: float) -> str:
    """Label of a value of m in tables and CSV: the shortest form, e.g. ``'0.075'``.

    Examples
    --------
    >>> m_label(0.07500000000000001), m_label(0), m_label(0.5)
    ('0.075', '0', '0.5')
    """
    return format(round(float(m), 6), "g")


# --------------------------------------------------------------------------- result values


@dataclass(frozen=True)
class RunRow:
    """One scored run: one map pair, one annotator's ground truth, one matcher, variant and m.

    Human-vs-human rows have ``matcher='human'``, ``variant`` = the annotator whose cliques were
    scored, ``annotator`` = the reference annotator, ``m_label='-'`` and ``m_value`` NaN.
    """

    map: str
    annotator: str
    matcher: str
    variant: str
    m_label: str
    m_value: float
    tp: int
    fp: int
    fn: int
    precision: float
    recall: float
    f1: float
    seeds: int
    n_sketch_regions: int
    n_metric_regions: int
    time_s: float
    model: str = ""
    n_pairs: int = 0
    scoring: str = "correct"
    reason: str = ""


#: Column order of runs.csv (the RunRow fields).
RUN_COLUMNS = tuple(f.name for f in dataclasses.fields(RunRow))


@dataclass(frozen=True)
class Summary:
    """F1 over the maps of one (annotator, matcher, variant) for one way of choosing m.

    Attributes
    ----------
    annotator : str
        An annotator, or ``'all'`` for every (map, annotator) pooled.
    matcher, variant : str
        For ``choice='human'``: ``'human'`` and the annotator scored against ``annotator``.
    choice : {'oracle', 'fixed', 'auto', 'human'}
    maps : tuple of str
        Map names (``'map/annotator'`` when pooled), in the order of the values.
    f1, precision, recall : tuple of float
        One value per map.
    m_values : tuple of float
        The m used for each map (NaN for human rows).
    fixed_m : str
        For ``choice='fixed'``: the label of the chosen m; else ''.
    """

    annotator: str
    matcher: str
    variant: str
    choice: str
    maps: tuple[str, ...]
    f1: tuple[float, ...]
    precision: tuple[float, ...]
    recall: tuple[float, ...]
    m_values: tuple[float, ...]
    fixed_m: str = ""

    @property
    def n(self) -> int:
        return len(self.f1)

    @property
    def median(self) -> float:
        return float(statistics.median(self.f1)) if self.f1 else math.nan

    @property
    def mean(self) -> float:
        return float(statistics.fmean(self.f1)) if self.f1 else math.nan

    @property
    def sd(self) -> float:
        """Sample standard deviation (n - 1); NaN for fewer than two maps."""
        return float(statistics.stdev(self.f1)) if len(self.f1) > 1 else math.nan

    @property
    def mean_precision(self) -> float:
        return float(statistics.fmean(self.precision)) if self.precision else math.nan

    @property
    def mean_recall(self) -> float:
        return float(statistics.fmean(self.recall)) if self.recall else math.nan


@dataclass(frozen=True)
class EvaluationResult:
    """Everything an evaluation produced; summaries are computed on first access.

    Attributes
    ----------
    rows : tuple of RunRow
        Every matcher run, scored against every annotator.
    human_rows : tuple of RunRow
        Human-vs-human comparisons.
    experiments : tuple of Experiment
    settings : dict
        Dataset, matchers, variants, m grid, presets, scoring, workers, configuration (JSON-able).
    timings : dict
        ``segmentation_s``, ``matching_s``, ``total_s`` (wall clock), map counts.
    notes : tuple of str
        Observations worth reporting (e.g. ground-truth points that fell on no region).
    """

    rows: tuple[RunRow, ...] = ()
    human_rows: tuple[RunRow, ...] = ()
    experiments: tuple[Experiment, ...] = ()
    settings: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    @functools.cached_property
    def summaries(self) -> tuple[Summary, ...]:
        return summarise(self.rows, m_grid=self.settings.get("m_grid"))

    @functools.cached_property
    def human_summaries(self) -> tuple[Summary, ...]:
        return summarise_human(self.human_rows)

    @property
    def annotators(self) -> tuple[str, ...]:
        return tuple(dict.fromkeys(row.annotator for row in self.rows))

    def summary(self, annotator: str, matcher: str, variant: str, choice: str) -> Summary | None:
        """The summary of one table cell, or None when it was not run."""
        for item in self.summaries:
            if (item.annotator, item.matcher, item.variant, item.choice) == (annotator, matcher, variant, choice):
                return item
        return None


# --------------------------------------------------------------------------- summaries


def summarise(
    rows: Iterable[RunRow], *, pool: bool = True, m_grid: Sequence[float] | None = None
) -> tuple[Summary, ...]:
    """Oracle, best-fixed and automatic-m summaries of matcher runs.

    Parameters
    ----------
    rows : iterable of RunRow
        Human-vs-human rows are ignored.
    pool : bool, keyword-only
        Also summarise every (map, annotator) together under annotator ``'all'`` when there is
        more than one annotator.
    m_grid : sequence of float, keyword-only
        Restrict the oracle and fixed choices to these m values (default: every fixed m present).

    Returns
    -------
    tuple of Summary
        Ordered by annotator (first appearance, ``'all'`` last), matcher, variant, choice.

    Notes
    -----
    Ties pick the smallest m: for the oracle per map, and for the fixed m over maps. The fixed
    m is chosen among the values run on every map of the group.

    Examples
    --------
    >>> def row(name, m, f1):
    ...     label = m if m == "auto" else m_label(m)
    ...     value = 0.1 if m == "auto" else m
    ...     return RunRow(name, "ann", "planar", "T4", label, value, 0, 0, 0, f1, f1, f1, 0, 3, 3, 0.0)
    >>> rows = [row("a", 0.0, 0.2), row("a", 0.1, 0.8), row("b", 0.0, 0.6), row("b", 0.1, 0.4),
    ...         row("a", "auto", 0.8), row("b", "auto", 0.6)]
    >>> {s.choice: (round(s.mean, 2), s.fixed_m) for s in summarise(rows)}
    {'oracle': (0.7, ''), 'fixed': (0.6, '0.1'), 'auto': (0.7, '')}
    """
    rows = [row for row in rows if row.matcher != HUMAN]
    grid_labels = None if m_grid is None else {m_label(m) for m in m_grid}
    annotators = list(dict.fromkeys(row.annotator for row in rows))
    groups: dict[str, list[RunRow]] = {annotator: [] for annotator in annotators}
    for row in rows:
        groups[row.annotator].append(row)
    if pool and len(annotators) > 1:
        groups[POOLED] = [dataclasses.replace(row, map=f"{row.map}/{row.annotator}") for row in rows]

    summaries: list[Summary] = []
    for annotator, group_rows in groups.items():
        by_method: dict[tuple[str, str], list[RunRow]] = {}
        for row in group_rows:
            by_method.setdefault((row.matcher, row.variant), []).append(row)
        for (matcher, variant), method_rows in _ordered_methods(by_method):
            summaries.extend(_summaries_of_method(annotator, matcher, variant, method_rows, grid_labels))
    return tuple(summaries)


def _ordered_methods(by_method: dict) -> list:
    def key(item):
        matcher, variant = item[0]
        return (_rank(matcher, MATCHERS), matcher, _rank(variant, VARIANTS), variant)

    return sorted(by_method.items(), key=key)


def _rank(value: str, order: Sequence[str]) -> int:
    return order.index(value) if value in order else len(order)


def _summaries_of_method(annotator, matcher, variant, rows, grid_labels) -> list[Summary]:
    maps = list(dict.fromkeys(row.map for row in rows))
    fixed: dict[str, dict[str, RunRow]] = {}  # map -> m label -> row
    auto: dict[str, RunRow] = {}
    for row in rows:
        if row.m_label == AUTO:
            auto[row.map] = row
        elif grid_labels is None or row.m_label in grid_labels:
            fixed.setdefault(row.map, {})[row.m_label] = row

    result = []
    swept_maps = [name for name in maps if fixed.get(name)]
    if swept_maps:
        # Oracle: per map the best F1 of the grid; smallest m on ties.
        best_rows = [
            max(sorted(fixed[name].values(), key=lambda r: r.m_value), key=lambda r: r.f1) for name in swept_maps
        ]
        result.append(_summary(annotator, matcher, variant, "oracle", swept_maps, best_rows))

        common = set.intersection(*(set(fixed[name]) for name in swept_maps))
        if common:
            labels = sorted(common, key=lambda label: fixed[swept_maps[0]][label].m_value)
            means = [statistics.fmean(fixed[name][label].f1 for name in swept_maps) for label in labels]
            chosen = labels[int(np.argmax(means))]  # argmax keeps the first (smallest m) on ties
            chosen_rows = [fixed[name][chosen] for name in swept_maps]
            result.append(_summary(annotator, matcher, variant, "fixed", swept_maps, chosen_rows, fixed_m=chosen))
    auto_maps = [name for name in maps if name in auto]
    if auto_maps:
        result.append(_summary(annotator, matcher, variant, "auto", auto_maps, [auto[name] for name in auto_maps]))
    return result


def _summary(annotator, matcher, variant, choice, maps, rows, *, fixed_m: str = "") -> Summary:
    return Summary(
        annotator=annotator,
        matcher=matcher,
        variant=variant,
        choice=choice,
        maps=tuple(maps),
        f1=tuple(float(r.f1) for r in rows),
        precision=tuple(float(r.precision) for r in rows),
        recall=tuple(float(r.recall) for r in rows),
        m_values=tuple(float(r.m_value) for r in rows),
        fixed_m=fixed_m,
    )


def summarise_human(rows: Iterable[RunRow]) -> tuple[Summary, ...]:
    """One summary per (reference annotator, scored annotator) of human-vs-human rows.

    Examples
    --------
    >>> rows = [RunRow(name, "a", "human", "b", "-", math.nan, 1, 0, 0, 1.0, 1.0, f1, 0, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> [(s.annotator, s.variant, s.mean) for s in summarise_human(rows)]
    [('a', 'b', 0.75)]
    """
    groups: dict[tuple[str, str], list[RunRow]] = {}
    for row in rows:
        if row.matcher == HUMAN:
            groups.setdefault((row.annotator, row.variant), []).append(row)
    return tuple(
        _summary(reference, HUMAN, scored, HUMAN, [r.map for r in group], group)
        for (reference, scored), group in groups.items()
    )


def mean_f1_by_m(rows: Iterable[RunRow]) -> dict[tuple[str, str, str], list[tuple[float, str, float, int]]]:
    """Mean F1 over maps for every fixed m, per (annotator, matcher, variant).

    Returns
    -------
    dict
        ``(annotator, matcher, variant) -> [(m_value, m_label, mean_f1, n_maps), ...]`` sorted by m.
        The automatic m is left out (see the ``auto`` summaries).

    Examples
    --------
    >>> rows = [RunRow(name, "a", "planar", "T4", "0.1", 0.1, 0, 0, 0, 0, 0, f1, 0, 3, 3, 0.0)
    ...         for name, f1 in (("00", 1.0), ("01", 0.5))]
    >>> mean_f1_by_m(rows)
    {('a', 'planar', 'T4'): [(0.1, '0.1', 0.75, 2)]}
    """
    values: dict[tuple[str, str, str], dict[str, list]] = {}
    m_of: dict[str, float] = {}
    for row in rows:
        if row.matcher == HUMAN or row.m_label == AUTO:
            continue
        values.setdefault((row.annotator, row.matcher, row.variant), {}).setdefault(row.m_label, []).append(row.f1)
        m_of[row.m_label] = row.m_value
    return {
        key: sorted(((m_of[label], label, float(statistics.fmean(f1s)), len(f1s)) for label, f1s in per_m.items()))
        for key, per_m in values.items()
    }


# --------------------------------------------------------------------------- the runner


def run_evaluation(
    dataset_dir: str | Path | Sequence[Experiment],
    *,
    matchers: Sequence[str] = MATCHERS,
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
    from ursim_core.matching import MatchConfig
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
    # Per experiment (same order): the (input map, model map) segmentation jobs.
    input_jobs: list[tuple[_SegmentationJob, _SegmentationJob]] = []
    digests: dict[Path, str] = {}
    for experiment in experiments:
        input_preset = preset or ("ursim-released" if released else MATCH_PRESETS["sketch"])
        model_preset = metric_preset or ("ursim-released" if released else MATCH_PRESETS["metric"])
        input_jobs.append(
            (
                _SegmentationJob.of(experiment.sketch, input_preset, load_options, digests),
                _SegmentationJob.of(experiment.metric, model_preset, load_options, digests),
            )
        )
    distinct_jobs = list(dict.fromkeys(job for pair in input_jobs for job in pair))
    for preset_name in sorted({job.preset for job in distinct_jobs}):
        # An unknown preset is reported now, not by a worker process after other maps ran.
        resolve_params("maoris", preset_name)

    n_tasks = len(experiments) * len(matchers) * len(variants)
    total_steps = len(distinct_jobs) + n_tasks + (1 if human else 0)
    reporter = _Progress(progress, total_steps)

    segment_started = time.perf_counter()
    segmentations, cached = _segment_all(distinct_jobs, workers, reporter, segmentation_cache, cache_dir)
    segmentation_s = time.perf_counter() - segment_started

    references, notes = _references(experiments, input_jobs, segmentations)
    match_started = time.perf_counter()
    tasks = [
        _MatchTask(
            name=experiment.name,
            model=_model_label(experiment),
            sketch_key=jobs[0].key,
            metric_key=jobs[1].key,
            matcher=matcher,
            variant=variant,
            config=_config_for(base_config, matcher, variant, released),
            m_grid=tuple(m_grid),
            references=reference,
            legacy=legacy_mode,
            auto_m=auto_m,
        )
        for experiment, jobs, reference in zip(experiments, input_jobs, references)
        for matcher in matchers
        for variant in variants
    ]
    rows = _run_tasks(tasks, segmentations, workers, reporter)
    matching_s = time.perf_counter() - match_started

    human_rows: list[RunRow] = []
    if human:
        human_rows = _human_rows(experiments, input_jobs, segmentations, references, legacy_mode)
        reporter.step("human vs human")

    settings = {
        "dataset": None if dataset is None else str(dataset),
        "matchers": list(matchers),
        "variants": list(variants),
        "m_grid": [float(m) for m in m_grid],
        "auto_m": auto_m,
        "preset": preset,
        "metric_preset": metric_preset,
        "presets_used": sorted({job.preset for job in distinct_jobs}),
        "load_options": load_options,
        "scoring": legacy_mode,
        "released": released,
        "workers": workers,
        "config": _config_summary(base_config),
        "config_overrides": overrides,
        "n_experiments": len(experiments),
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
        experiments=tuple(experiments),
        settings=settings,
        timings=timings,
        notes=tuple(notes),
    )


def _model_label(experiment: Experiment) -> str:
    """The model map as a path inside the dataset without suffix (``model/model_simple``,
    ``GT/Malcolm/model_simple``): unique where the file names are not."""
    metric = Path(experiment.metric)
    if experiment.dataset is not None:
        try:
            return metric.relative_to(experiment.dataset).with_suffix("").as_posix()
        except ValueError:
            pass
    return metric.stem


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


def _config_for(base, matcher: str, variant: str, released: bool):
    changes: dict[str, Any] = {"matcher": matcher, "variant": variant, "m": AUTO}
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


class _Progress:
    def __init__(self, callback: ProgressCallback | None, total: int):
        self.callback = callback
        self.total = total
        self.done = 0

    def step(self, text: str) -> None:
        self.done += 1
        if self.callback is not None:
            self.callback(self.done, self.total, text)


# --------------------------------------------------------------------------- segmentation


@dataclass(frozen=True)
class _SegmentationJob:
    """One map to segment. Equal jobs (same file content, preset and loading) share a result,
    so a model stored under two names (Halmstad: GT/Malcolm/model_simple.png = E5_08.png) and a
    map used by several experiments are segmented once."""

    path: Path = field(compare=False)
    digest: str
    preset: str
    load_key: str

    @classmethod
    def of(cls, path: Path, preset: str, load: dict, digests: dict[Path, str]) -> _SegmentationJob:
        path = Path(path)
        if path not in digests:
            try:
                digests[path] = hashlib.sha256(path.read_bytes()).hexdigest()
            except OSError:
                # load_map reports the real problem, naming the file, when the map is loaded.
                digests[path] = f"unreadable:{path.resolve()}"
        return cls(path=path, digest=digests[path], preset=preset, load_key=json.dumps(load, sort_keys=True))

    @property
    def key(self) -> str:
        return f"{self.digest}|{self.preset}|{self.load_key}"

    @property
    def load(self) -> dict:
        return json.loads(self.load_key)


def _segment_job(job: _SegmentationJob):
    """Load and segment one map (runs in a worker process)."""
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import segment

    return segment(load_map(job.path, **job.load), preset=job.preset)


@functools.lru_cache(maxsize=1)
def _segmenter_code_digest() -> str:
    """Digest of every source file of the segmentation package: a cached result is stale when any changes."""
    import ursim_core.segmentation as package

    digest = hashlib.sha256()
    root = Path(package.__file__).parent
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _disk_cache_path(cache_dir: Path, job: _SegmentationJob) -> Path:
    from ursim_core.segmentation import resolve_params

    # The resolved parameters (not only the preset name) and the segmenter's source go in the
    # key, so a changed preset definition or a changed MAORIS implementation invalidates the cache.
    identity = json.dumps(
        {
            "sha256": job.digest,
            "params": resolve_params("maoris", job.preset),
            "load": job.load,
            "version": 1,
            "code": _segmenter_code_digest(),
        },
        sort_keys=True,
    )
    return cache_dir / f"{job.path.stem}-{hashlib.sha256(identity.encode()).hexdigest()[:24]}.npz"


def _read_disk_cache(path: Path, job: _SegmentationJob):
    from ursim_core.segmentation import Segmentation, resolve_params
    from ursim_core.segmentation.graph import region_graph

    try:
        with np.load(path) as stored:
            labels = stored["labels"].astype(np.int32)
    except (OSError, KeyError, ValueError):
        # A missing, damaged or foreign cache file is only a cache miss.
        return None
    return Segmentation(
        labels=labels, graph=region_graph(labels), method="maoris", params=resolve_params("maoris", job.preset)
    )


def _write_disk_cache(path: Path, segmentation) -> None:
    from ursim_core.io.atomic import atomic_write_bytes

    buffer = io.BytesIO()
    np.savez_compressed(buffer, labels=segmentation.labels)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, buffer.getvalue())
    except OSError:
        # A read-only or full cache folder must not fail the evaluation.
        pass


def _segment_all(jobs, workers: int, reporter: _Progress, memory_cache, cache_dir):
    """Segmentations by job key, from the caches or computed biggest map first."""
    segmentations: dict[str, Any] = {}
    cache_folder = None if cache_dir is None else Path(cache_dir)
    to_run = []
    for job in jobs:
        found = None
        if memory_cache is not None:
            found = memory_cache.get(job.key)
        if found is None and cache_folder is not None:
            found = _read_disk_cache(_disk_cache_path(cache_folder, job), job)
            if found is not None and memory_cache is not None:
                memory_cache[job.key] = found
        if found is None:
            to_run.append(job)
        else:
            segmentations[job.key] = found
            reporter.step(f"segment {job.path.name} (cached)")
    cached = len(jobs) - len(to_run)
    # Biggest maps first so the workers finish together.
    to_run.sort(key=lambda job: -_pixel_count(job.path))
    for job, segmentation in _completed(_segment_job, to_run, workers=workers):
        segmentations[job.key] = segmentation
        if memory_cache is not None:
            memory_cache[job.key] = segmentation
        if cache_folder is not None:
            _write_disk_cache(_disk_cache_path(cache_folder, job), segmentation)
        reporter.step(f"segment {job.path.name}: {segmentation.n_regions} regions")
    return segmentations, cached


def _completed(function, items, *, workers: int, initializer=None, initargs=()):
    """Yield ``(item, function(item))`` as each finishes, on ``workers`` processes.

    With one worker (or one item) everything runs here, in order, with no process start-up
    cost; ``initializer`` only concerns worker processes. On an error or an interruption the
    pending items are cancelled before it propagates, so a failure does not wait for the rest.
    """
    if workers <= 1 or len(items) < 2:
        for item in items:
            yield item, function(item)
        return
    pool = concurrent.futures.ProcessPoolExecutor(max_workers=workers, initializer=initializer, initargs=initargs)
    try:
        futures = {pool.submit(function, item): item for item in items}
        for future in concurrent.futures.as_completed(futures):
            yield futures[future], future.result()
    except BaseException:
        pool.shutdown(wait=True, cancel_futures=True)
        raise
    pool.shutdown(wait=True)


def _pixel_count(path: Path) -> int:
    try:
        from PIL import Image

        with Image.open(path) as image:
            return image.width * image.height
    except Exception:
        return 0


# --------------------------------------------------------------------------- ground truth


def _references(experiments, input_jobs, segmentations):
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
class _MatchTask:
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


def _run_task_in_worker(task: _MatchTask) -> list[RunRow]:
    return _run_task(task, _WORKER_SEGMENTATIONS)


def _run_task(task: _MatchTask, segmentations: dict[str, Any]) -> list[RunRow]:
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


def _run_tasks(
    tasks: list[_MatchTask], segmentations: dict[str, Any], workers: int, reporter: _Progress
) -> list[RunRow]:
    # Largest problems first so the workers finish together; the segmentations reach each
    # worker once through the pool initializer instead of once per task.
    order = sorted(
        tasks, key=lambda t: -(segmentations[t.sketch_key].n_regions * segmentations[t.metric_key].n_regions)
    )
    if workers <= 1 or len(order) < 2:
        completed = _completed(functools.partial(_run_task, segmentations=segmentations), order, workers=1)
    else:
        completed = _completed(
            _run_task_in_worker, order, workers=workers, initializer=_init_worker, initargs=(segmentations,)
        )
    rows: list[RunRow] = []
    for task, task_rows in completed:
        rows.extend(task_rows)
        reporter.step(f"match {task.name} {task.matcher} {task.variant}")
    position = {(t.name, t.model, t.matcher, t.variant): index for index, t in enumerate(tasks)}
    m_position = {label: i for i, label in enumerate([m_label(m) for m in tasks[0].m_grid] + [AUTO])} if tasks else {}
    rows.sort(
        key=lambda r: (position[(r.map, r.model, r.matcher, r.variant)], r.annotator, m_position.get(r.m_label, 0))
    )
    return rows


# --------------------------------------------------------------------------- human vs human


def _human_rows(experiments, input_jobs, segmentations, references, legacy_mode) -> list[RunRow]:
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
                        model=_model_label(experiment),
                        n_pairs=len(score.pairs),
                        scoring=score.mode,
                    )
                )
    return rows


# --------------------------------------------------------------------------- report entry points


def format_tables(result: EvaluationResult) -> str:
    """Table-1-style text tables of a result (see :func:`ursim_core.evaluation.report.format_tables`)."""
    from ursim_core.evaluation.report import format_tables as _format_tables

    return _format_tables(result)


def write_report(result: EvaluationResult, out_dir: str | Path) -> dict[str, Path]:
    """Write runs.csv, summary.md and the plots (see :func:`ursim_core.evaluation.report.write_report`)."""
    from ursim_core.evaluation.report import write_report as _write_report

    return _write_report(result, out_dir)
