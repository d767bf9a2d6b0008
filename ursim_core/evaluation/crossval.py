"""Leave-one-sketch-out cross-validation of a matching option chosen on a dataset.

A value chosen because it scores best on the same sketches it is reported on flatters the figure.
:func:`cross_validate` takes one evaluation per candidate value of an option (``ursim evaluate
--cross-validate NAME=V1,V2,...``) and, for every map in turn, chooses the value on the *other* maps
(highest mean of F1 and place accuracy over their annotators and orientations, with the automatic
m) and scores the held-out map with it. The held-out figures are the honest ones; the in-sample
best value is reported beside them, labelled as such.
"""

from __future__ import annotations

import json
import math
import re
from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.evaluation.formatting import markdown_table, number, text_table
from ursim_core.evaluation.results import AUTO

__all__ = ["CrossValidation", "parse_option", "parse_choices", "cross_validate"]


def _value(text: str) -> Any:
    try:
        return json.loads(text)
    except ValueError:
        return text


def parse_option(text: str) -> tuple[str, Any]:
    """``'NAME=VALUE'`` as ``(name, value)``; the value read as JSON when it is (numbers, true).

    Examples
    --------
    >>> parse_option("orientation=upright"), parse_option("position_weight=1.5")
    (('orientation', 'upright'), ('position_weight', 1.5))
    """
    name, sep, value = text.partition("=")
    if not sep or not name.strip() or not value.strip():
        raise ParameterError(f"expected NAME=VALUE, not {text!r}", field="set")
    return name.strip(), _value(value.strip())


def parse_choices(text: str) -> tuple[str, list[Any]]:
    """``'NAME=V1,V2,...'`` as ``(name, [values])``, at least two distinct values.

    Examples
    --------
    >>> parse_choices("orientation_overlap=0,0.5,1")
    ('orientation_overlap', [0, 0.5, 1])
    """
    name, sep, values = text.partition("=")
    parsed = [_value(v.strip()) for v in values.split(",") if v.strip()]
    if not sep or not name.strip() or len(parsed) < 2 or len({json.dumps(v) for v in parsed}) < len(parsed):
        raise ParameterError(
            f"expected NAME=V1,V2,... with two or more distinct values, not {text!r}", field="cross_validate"
        )
    return name.strip(), parsed


@dataclass(frozen=True)
class CrossValidation:
    """Held-out figures of an option chosen per fold.

    Attributes
    ----------
    option : str
    values : tuple
        The candidate values, in the order given (ties go to the earlier one).
    rows : tuple of (map, chosen value, f1, place accuracy)
        Per held-out map: the value chosen on the other maps and the map's mean F1 and place
        accuracy with it (over annotators and orientations).
    by_orientation : dict
        Orientation name ('' = as drawn) -> (mean F1, mean place accuracy) of the held-out runs.
    in_sample : dict
        Value -> (mean F1, mean place accuracy) over every map: what choosing on the same data shows.
    """

    option: str
    values: tuple
    rows: tuple
    by_orientation: dict
    in_sample: dict

    @property
    def f1(self) -> float:
        return float(np.mean([row[2] for row in self.rows]))

    @property
    def place_accuracy(self) -> float:
        return float(np.nanmean([row[3] for row in self.rows]))

    @property
    def worst(self) -> tuple:
        """The held-out row with the lowest F1."""
        return min(self.rows, key=lambda row: row[2])

    def table(self, *, markdown: bool = False) -> str:
        """Per-map table, then the means, the worst map and the in-sample figures."""
        header = ["map", f"{self.option} chosen on the others", "held-out F1", "held-out place acc."]
        body = [[name, json.dumps(value), number(f1), number(place)] for name, value, f1, place in self.rows]
        body.append(["mean", "", number(self.f1), number(self.place_accuracy)])
        worst = self.worst
        body.append([f"worst ({worst[0]})", "", number(worst[2]), number(worst[3])])
        for orientation, (f1, place) in sorted(self.by_orientation.items(), key=lambda item: _natural(item[0])):
            body.append([f"orientation {orientation or 'as drawn'}", "", number(f1), number(place)])
        for value, (f1, place) in self.in_sample.items():
            body.append([f"in-sample {self.option}={json.dumps(value)}", "(same data)", number(f1), number(place)])
        return (markdown_table if markdown else text_table)(header, body)


def _natural(text: str) -> tuple:
    """'rot15' before 'rot105': numbers compared as numbers."""
    return tuple(int(part) if part.isdigit() else part for part in re.split(r"(\d+)", text))


def _per_map(result, matcher: str, variant: str) -> dict[str, dict[str, list[tuple[float, float]]]]:
    """map -> orientation -> [(f1, place accuracy)] of the automatic-m runs."""
    table: dict[str, dict[str, list]] = defaultdict(lambda: defaultdict(list))
    for row in result.rows:
        if row.matcher == matcher and row.variant == variant and row.m_label == AUTO:
            table[row.map][row.augment].append((row.f1, row.place_accuracy))
    return table


def _mean(pairs: Sequence[tuple[float, float]], column: int) -> float:
    values = [pair[column] for pair in pairs if not math.isnan(pair[column])]
    return float(np.mean(values)) if values else math.nan


def cross_validate(
    results: Mapping[Any, Any], *, option: str, matcher: str = "planar", variant: str = "T4"
) -> CrossValidation:
    """Leave-one-map-out choice of ``option`` among the values keying ``results``.

    Parameters
    ----------
    results : mapping of value -> EvaluationResult
        One evaluation per candidate value, same maps (and augmentation), in the order to try.
    option : str, keyword-only
        The option's name, for the table.
    matcher, variant : str, keyword-only
        Which runs of the evaluations to use (those with the automatic m).

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> def run(name, f1): return NS(map=name, matcher="planar", variant="T4", m_label="auto",
    ...                               augment="", f1=f1, place_accuracy=f1)
    >>> results = {0: NS(rows=[run("a", .9), run("b", .2), run("c", .5)]),
    ...            1: NS(rows=[run("a", .1), run("b", .8), run("c", .6)])}
    >>> cv = cross_validate(results, option="k")
    >>> [(name, value) for name, value, *_ in cv.rows]
    [('a', 1), ('b', 0), ('c', 0)]
    >>> round(cv.f1, 3)
    0.267
    """
    values = list(results)
    if len(values) < 2:
        raise ParameterError("needs evaluations for two or more values", field="cross_validate")
    tables = {value: _per_map(results[value], matcher, variant) for value in values}
    maps = sorted(set.intersection(*(set(table) for table in tables.values())))
    if len(maps) < 2:
        raise ParameterError(
            f"needs two or more maps with automatic-m runs of {matcher} {variant}", field="cross_validate"
        )

    # Each map's runs (annotators x orientations) pooled, and its score: mean of F1 and place
    # accuracy (F1 alone where no place could be scored), once per value.
    pooled = {
        value: {name: [run for runs in tables[value][name].values() for run in runs] for name in maps}
        for value in values
    }

    def score_of(runs) -> float:
        f1, place = _mean(runs, 0), _mean(runs, 1)
        return f1 if math.isnan(place) else (f1 + place) / 2

    scores = {value: {name: score_of(pooled[value][name]) for name in maps} for value in values}
    rows = []
    held_out: dict[str, list] = defaultdict(list)
    for name in maps:
        fold = [float(np.mean([scores[value][other] for other in maps if other != name])) for value in values]
        chosen = values[int(np.argmax(fold))]
        runs = pooled[chosen][name]
        rows.append((name, chosen, _mean(runs, 0), _mean(runs, 1)))
        for orientation, orientation_runs in tables[chosen][name].items():
            held_out[orientation].extend(orientation_runs)
    by_orientation = {key: (_mean(runs, 0), _mean(runs, 1)) for key, runs in held_out.items()}
    in_sample = {}
    for value in values:
        runs = [run for name in maps for run in pooled[value][name]]
        in_sample[value] = (_mean(runs, 0), _mean(runs, 1))
    return CrossValidation(option, tuple(values), tuple(rows), by_orientation, in_sample)
