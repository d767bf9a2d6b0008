"""The values an evaluation produces (one :class:`RunRow` per scored run) and their summaries.

Summaries (:func:`summarise`): for each annotator (and all annotators pooled) and each matcher x
variant, the F1 over maps with

- ``oracle``: the best m of the grid for each map (what the paper's Table 1 reports),
- ``fixed``: the single m of the grid with the best mean F1 over the maps,
- ``auto``: the automatic choice of m (:mod:`ursim_core.matching.auto_m`),

as median and mean +- sample sd. Both the runner (:mod:`~ursim_core.evaluation.runner`) and the
report modules import from here; nothing here imports them.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ursim_core.evaluation.layouts import Experiment

__all__ = [
    "DEFAULT_M_GRID",
    "MATCHERS",
    "DEFAULT_MATCHERS",
    "VARIANTS",
    "CHOICES",
    "POOLED",
    "HUMAN",
    "CEILING",
    "AUTO",
    "RUN_COLUMNS",
    "RunRow",
    "Summary",
    "EvaluationResult",
    "m_label",
    "summarise",
    "summarise_human",
    "mean_f1_by_m",
]

#: The released driver's sweep of m: 0, 0.025, ..., 0.475 (20 values).
DEFAULT_M_GRID: tuple[float, ...] = tuple(round(0.025 * i, 10) for i in range(20))
#: Matchers in the order of the report's rows.
MATCHERS = ("auto", "planar", "hungarian", "vf2", "overlay")
#: The matchers an evaluation runs when none are named. 'auto' is what ``ursim match`` runs by
#: default: the planar matcher for sketches, the overlay matcher for metric maps (the layout says
#: which its inputs are; :meth:`ursim_core.matching.MatchConfig.resolved`).
DEFAULT_MATCHERS = ("auto", "hungarian", "vf2")
#: Descriptor variants in the order of the paper's Table 1 columns.
VARIANTS = ("baseline", "T1", "T2", "T3", "T4")
#: How m is chosen in a summary.
CHOICES = ("oracle", "fixed", "auto")
#: Annotator name of the summaries that pool every annotator's (map, annotator) results.
POOLED = "all"
#: Matcher name of the human-vs-human rows.
HUMAN = "human"
#: Matcher name of the rows of the one-to-one ceiling (:mod:`ursim_core.evaluation.ceiling`).
CEILING = "ceiling"
AUTO = "auto"


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

    ``place_accuracy`` is :func:`ursim_core.evaluation.place.place_accuracy` of the same pairs
    (NaN when no clique could be scored); ``augment`` the orientation of the sketch
    (:attr:`ursim_core.evaluation.augment.Orientation.name`, '' when the run was not augmented).
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
    place_accuracy: float = math.nan
    augment: str = ""

    @property
    def sample(self) -> str:
        """The map and orientation: ``'00'``, or ``'00@rot90'`` for an augmented run."""
        return f"{self.map}@{self.augment}" if self.augment else self.map


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
    choice : {'oracle', 'fixed', 'auto', 'human', 'ceiling'}
    maps : tuple of str
        Map names (``'map/annotator'`` when pooled), in the order of the values.
    f1, precision, recall, place : tuple of float
        One value per map (``place``: place accuracy, NaN where none could be scored). Augmented
        runs are separate samples, named ``'map@orientation'``.
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
    place: tuple[float, ...] = ()

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

    @property
    def mean_place(self) -> float:
        """Mean place accuracy over the maps where it could be scored (NaN when none)."""
        values = [value for value in self.place if not math.isnan(value)]
        return float(statistics.fmean(values)) if values else math.nan


@dataclass(frozen=True)
class EvaluationResult:
    """Everything an evaluation produced; summaries are computed on first access.

    Attributes
    ----------
    rows : tuple of RunRow
        Every matcher run, scored against every annotator.
    human_rows : tuple of RunRow
        Human-vs-human comparisons.
    ceiling_rows : tuple of RunRow
        The best one-to-one answer against every annotator at once, scored against each
        (``matcher='ceiling'``; :mod:`ursim_core.evaluation.ceiling`).
    experiments : tuple of Experiment
    settings : dict
        Dataset, matchers, variants, m grid, presets, scoring, workers, configuration (JSON-able).
    timings : dict
        ``segmentation_s``, ``matching_s``, ``total_s`` (wall clock), map counts.
    notes : tuple of str
        Observations worth reporting (e.g. ground-truth points that fell on no region).
    warnings : tuple of str
        The notes a user must see at once (e.g. a map scored against one annotator only
        because the other's file is missing); also in ``notes``.
    """

    rows: tuple[RunRow, ...] = ()
    human_rows: tuple[RunRow, ...] = ()
    ceiling_rows: tuple[RunRow, ...] = ()
    experiments: tuple[Experiment, ...] = ()
    settings: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @functools.cached_property
    def summaries(self) -> tuple[Summary, ...]:
        return summarise(self.rows, m_grid=self.settings.get("m_grid"))

    @functools.cached_property
    def human_summaries(self) -> tuple[Summary, ...]:
        return summarise_human(self.human_rows)

    @functools.cached_property
    def ceiling_summary(self) -> Summary | None:
        """The ceiling rows over every (map, annotator) pooled, or None when there are none."""
        rows = self.ceiling_rows
        if not rows:
            return None
        variant = "one-to-one" if all(r.variant == "one-to-one" for r in rows) else "one-to-one, lower bound"
        return _summary(POOLED, CEILING, variant, CEILING, [f"{r.sample}/{r.annotator}" for r in rows], rows)

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
    # Each (map, orientation) is a sample of its own.
    rows = [dataclasses.replace(row, map=row.sample) for row in rows if row.matcher != HUMAN]
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
        place=tuple(float(r.place_accuracy) for r in rows),
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
        _summary(reference, HUMAN, scored, HUMAN, [r.sample for r in group], group)
        for (reference, scored), group in groups.items()
    )


def mean_f1_by_m(
    rows: Iterable[RunRow], *, value: str = "f1"
) -> dict[tuple[str, str, str], list[tuple[float, str, float, int]]]:
    """Mean F1 (or another value: ``value="place_accuracy"``) over maps for every fixed m,
    per (annotator, matcher, variant). NaN values (no scorable clique) are left out of a mean.

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
        number = float(getattr(row, value))
        if math.isnan(number):
            continue
        values.setdefault((row.annotator, row.matcher, row.variant), {}).setdefault(row.m_label, []).append(number)
        m_of[row.m_label] = row.m_value
    return {
        key: sorted(
            ((m_of[label], label, float(statistics.fmean(items)), len(items)) for label, items in per_m.items())
        )
        for key, per_m in values.items()
    }
