"""``ursim bench quality``: segmentation F1 of every preset, in-sample and leave-one-map-out.

A preset chosen on the maps it is scored on looks better than it will on a new map, so each
preset chosen on data is reported twice: in-sample (the candidate of its grid chosen on all
maps) and leave-one-map-out (the candidate chosen without the map scored), per map and per
annotator, with the annotators' agreement as the reference line
(:func:`ursim_core.segmentation.presets_cv.cross_validate`; learned merging:
:func:`ursim_core.segmentation.learned_cv.cross_validate_learned`, a model trained without
the map). Presets not chosen on these maps have equal columns.

:func:`cross_validate_rule` gives the same two figures for one segmenter and preset on any
maps with ground truth; ``ursim segment --evaluate`` uses it.
"""

from __future__ import annotations

import csv
from pathlib import Path
from typing import Any

__all__ = ["bench_quality", "cross_validate_rule", "data_chosen_rule", "print_cross_validation"]

#: Presets chosen on data, ``(method, preset) -> (kind of maps, name of its selection rule)``
#: (:func:`ursim_core.segmentation.presets_cv.default_selections`); learned merging is
#: trained on data whatever its preset.
_RULES = {
    ("maoris", "sketch"): ("sketches", "sketch"),
    ("watershed", "robot"): ("robot_maps", "watershed"),
    ("watershed", "default"): ("robot_maps", "watershed"),
}


def data_chosen_rule(method: str, preset: str | None) -> str | None:
    """The name of the selection rule a preset was chosen by, or None when it was not.

    Examples
    --------
    >>> data_chosen_rule("maoris", "sketch"), data_chosen_rule("maoris", "default")
    ('sketch', None)
    """
    if method == "learned":
        return "learned"
    rule = _RULES.get((method, preset))
    return None if rule is None else rule[1]


def cross_validate_rule(benchmark: list, method: str, preset: str | None):
    """In-sample and leave-one-map-out figures of one data-chosen preset on ``benchmark``.

    Returns a :class:`~ursim_core.segmentation.presets_cv.CrossValidation` with one row per
    map and annotator, or None when the preset was not chosen on data (its figure is the
    same either way).
    """
    from ursim_core.segmentation.presets_cv import cross_validate, default_selections

    rule = data_chosen_rule(method, preset)
    if rule is None:
        return None
    if rule == "learned":
        from ursim_core.segmentation.learned_cv import cross_validate_learned

        return cross_validate_learned(benchmark)
    kind = next(kind for (m, p), (kind, name) in _RULES.items() if name == rule)
    return cross_validate(benchmark=benchmark, selections={rule: default_selections(kind)[rule]}, fixed={})


def print_cross_validation(cv, *, title: str) -> None:
    """Per map and annotator, then the summary (mean and worst), as text tables."""
    print(f"== {title}")
    presets = list(dict.fromkeys(row["preset"] for row in cv.rows))
    annotators = list(dict.fromkeys(row["annotator"] for row in cv.rows))
    maps = list(dict.fromkeys(row["map"] for row in cv.rows))
    agreement = {row["map"]: row["f1"] for row in cv.agreement}
    by_key = {(r["preset"], r["map"], r["annotator"]): r for r in cv.rows}
    columns = [f"{p} {a} {kind}" for p in presets for a in annotators for kind in ("in", "cv")]
    width = max(10, *(len(c) for c in columns))
    header = f"{'map':<8}" + "".join(f" {c:>{width}}" for c in columns)
    print(header + (f" {'agreement':>10}" if agreement else ""))
    for name in maps:
        cells = []
        for p in presets:
            for a in annotators:
                row = by_key.get((p, name, a))
                cells += ["-", "-"] if row is None else [f"{row['in_sample_f1']:.3f}", f"{row['cv_f1']:.3f}"]
        line = f"{name:<8}" + "".join(f" {cell:>{width}}" for cell in cells)
        print(line + (f" {agreement.get(name, float('nan')):>10.3f}" if agreement else ""))
    print(f"{'preset':<24} {'annotator':<12} {'maps':>4} {'in-sample':>9} {'worst':>6} {'cross-val':>9} {'worst':>6}")
    for row in cv.summary():
        print(
            f"{row['preset']:<24} {row['annotator']:<12} {row['maps']:>4} {row['in_sample_mean']:>9.3f} "
            f"{row['in_sample_worst']:>6.3f} {row['cv_mean']:>9.3f} {row['cv_worst']:>6.3f}"
        )
    print("(in-sample: the candidate chosen on all maps; cross-val: chosen, or trained, without the map scored)")


def bench_quality(
    dataset_root: str | Path,
    *,
    kinds: tuple[str, ...] = ("sketches", "robot_maps"),
    learned: bool = True,
    csv_path: str | Path | None = None,
) -> list[dict[str, Any]]:
    """Print the figures of every preset on ``maoris_segmentation``; return the rows.

    ``kinds``: "sketches" (two annotators and their agreement) and / or "robot_maps".
    ``learned``: also learned merging on the sketches (about 15 s of CPU). ``csv_path``:
    also write every row (kind, preset, map, annotator, in-sample and cross-validated F1,
    the choices) there, atomically.
    """
    from ursim_core.segmentation.presets_cv import cross_validate, load_benchmark

    rows: list[dict[str, Any]] = []
    for kind in kinds:
        benchmark = load_benchmark(dataset_root, kind)
        cv = cross_validate(benchmark=benchmark, maps=kind)
        if learned and kind == "sketches":
            from ursim_core.segmentation.learned_cv import cross_validate_learned
            from ursim_core.segmentation.presets_cv import CrossValidation

            extra = cross_validate_learned(benchmark)
            cv = CrossValidation(rows=cv.rows + extra.rows, agreement=cv.agreement)
        print_cross_validation(cv, title=f"segmentation F1, maoris_segmentation/{kind} ({len(benchmark)} maps)")
        rows += [{"kind": kind, **row} for row in cv.rows]
        rows += [{"kind": kind, "preset": "annotators' agreement", **row} for row in cv.agreement]
    if csv_path is not None:
        _write_csv(rows, Path(csv_path))
    return rows


def _write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    import io

    from ursim_core.io.atomic import atomic_write_text

    fields = list(dict.fromkeys(key for row in rows for key in row))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(path, buffer.getvalue())
    print(f"wrote {path}")
