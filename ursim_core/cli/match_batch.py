"""``ursim match-batch``: match many sketch/metric pairs listed in a manifest, on a pool or a cluster.

The manifest is a CSV with a header (columns ``sketch``, ``metric`` and optionally ``reference``,
``review`` and ``name``) or a JSON list of objects with those keys (``review``: a reviewed
correspondence file of the pair, as ``ursim match --review`` takes it). Relative paths are taken from the
manifest's folder. Each pair's outputs go to ``OUT/NAME/`` exactly as ``ursim match`` writes
them; ``OUT/summary.csv`` has one row per pair, with its status and, for a failed pair, the
error. A failed pair does not stop the others; the exit code is 1 when any failed.
"""

from __future__ import annotations

import argparse
import csv
import io
import os
import sys
from pathlib import Path
from typing import Any

from ursim_core.cli.common import check_output_folder, progress_bar
from ursim_core.errors import FormatError, ParameterError, UrsimError

HELP = "Match every sketch/metric pair of a manifest (CSV or JSON) and write one summary CSV."
EXAMPLES = """examples:
  ursim match-batch pairs.csv -o out/
  ursim match-batch pairs.json -o out/ --workers 2 --matcher planar
  ursim match-batch pairs.csv -o out/ --scheduler tcp://host:8786

pairs.csv:
  sketch,metric,reference,name
  sketches/00.png,model/model_simple.png,gt/gt_00_model_simple.dat,00"""

#: Columns of summary.csv, in order.
SUMMARY_COLUMNS = (
    "name",
    "sketch",
    "metric",
    "status",
    "error",
    "n_matches",
    "n_sketch_regions",
    "n_metric_regions",
    "m",
    "match_ms",
    "orientation_degrees",
    "orientation_mirrored",
    "resampling_votes",
    "pairs_from",
    "laid_by",
    "next_reading_gap",
    "precision",
    "recall",
    "f1",
    "place_accuracy",
    "reason",
)


def configure(parser: argparse.ArgumentParser) -> None:
    from ursim_core.cli.match_options import add_pair_options

    parser.add_argument(
        "manifest", metavar="MANIFEST", help="CSV (sketch,metric[,reference][,review][,name]) or JSON list"
    )
    parser.add_argument("-o", "--output", metavar="OUT", required=True, help="output folder")
    parser.add_argument("--workers", type=int, default=2, help="local processes (default 2)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run the pairs on a Dask cluster instead")
    # The options of `ursim match`, applied to every pair.
    add_pair_options(parser)


#: Largest manifest read: a million pairs of short paths.
MAX_MANIFEST_BYTES = 256 * 1024**2
#: The file match-batch writes beside the pairs' folders.
SUMMARY_NAME = "summary.csv"
# A pair's folder is staged as ".NAME.xxxxxxxx.tmp" (14 more bytes) and no name may exceed 255.
_MAX_NAME_BYTES = 240


def read_manifest(path: str | Path) -> list[dict[str, Any]]:
    """The pairs of a manifest: dicts with ``name``, ``sketch``, ``metric``, ``reference`` and ``review`` (or None).

    The manifest is read as every input is (a regular file, never a pipe; UTF-8 with or without
    a byte-order mark, as Excel saves "CSV UTF-8"), and every pair's name is checked before any
    pair runs (:func:`_check_name`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "p.csv").write_text("sketch,metric\\na/map.png,m.png\\nb/map.png,m.png\\n")
    >>> [(p["name"], p["sketch"].name) for p in read_manifest(folder / "p.csv")]
    [('001-map', 'map.png'), ('002-map', 'map.png')]
    """
    from ursim_core.io.reading import decode_text, parse_json, read_regular_file

    path = Path(path)
    raw = read_regular_file(path, max_bytes=MAX_MANIFEST_BYTES, error=FormatError, what="manifest")
    text = decode_text(raw, path, error=FormatError, what="manifest")
    if path.suffix.lower() == ".json":
        items = parse_json(text, path, error=FormatError, what="manifest")
        if not isinstance(items, list) or not all(isinstance(item, dict) for item in items):
            raise FormatError("expected a JSON list of objects with 'sketch' and 'metric'", path=path)
    else:
        try:
            reader = csv.DictReader(io.StringIO(text))
            if not reader.fieldnames or not {"sketch", "metric"} <= set(reader.fieldnames):
                raise FormatError("expected a CSV header with the columns sketch and metric", path=path)
            items = list(reader)
        except csv.Error as error:
            raise FormatError(f"not a CSV file: {error}", path=path) from None
    if not items:
        raise FormatError("the manifest lists no pair", path=path)
    pairs, names = [], {}
    for index, item in enumerate(items, start=1):
        for key in ("sketch", "metric"):
            if not isinstance(item.get(key), str) or not item[key].strip():
                raise FormatError(f"pair {index}: '{key}' must be a path", path=path)
        optional = {}
        for key in ("reference", "review"):
            value = item.get(key)
            if value is not None and not isinstance(value, str):
                raise FormatError(f"pair {index}: '{key}' must be a path", path=path)
            optional[key] = path.parent / value.strip() if value and value.strip() else None
        for key in ("sketch", "metric", "reference", "review"):
            if "\x00" in (item.get(key) or ""):
                raise FormatError(f"pair {index}: '{key}' contains a NUL character", path=path)
        sketch = path.parent / item["sketch"].strip()
        given = item.get("name")
        if given is not None and (isinstance(given, bool) or not isinstance(given, (str, int))):
            raise FormatError(f"pair {index}: 'name' must be a text (a folder name)", path=path)
        name = str(given or "").strip() or f"{index:03d}-{sketch.stem}"
        _check_name(name, index, names, path)
        names[name.casefold()] = index
        pairs.append(
            {
                "name": name,
                "sketch": sketch,
                "metric": path.parent / item["metric"].strip(),
                **optional,
            }
        )
    return pairs


def _check_name(name: str, index: int, taken: dict[str, int], manifest: Path) -> None:
    """Refuse a pair name that cannot be the folder ``OUT/NAME`` of this pair alone.

    Checked before any pair runs: otherwise a NUL stops the pair's staging with a traceback, a
    lone surrogate stops the summary after every pair has run, and a name equal to another's
    (also in another case: one folder on macOS and Windows) or to the summary's mixes outputs.
    """

    def refuse(problem: str) -> FormatError:
        shown = repr(name) if len(name) <= 60 else repr(name[:57]) + "..."
        return FormatError(f"pair {index}: the name {shown} {problem}; give the pair another 'name'", path=manifest)

    if any(ord(char) < 32 or ord(char) == 127 for char in name):
        raise refuse("contains a control character (NUL, newline, tab...)")
    if "/" in name or "\\" in name:
        raise refuse("contains a path separator (/ or \\): it must be one folder name")
    if name.startswith("."):
        raise refuse("starts with '.' (a hidden folder, '.' or '..')")
    try:
        encoded = name.encode("utf-8")
        os.fsencode(name)
    except UnicodeEncodeError:
        raise refuse("holds characters that are no text (lone surrogates)") from None
    if len(encoded) > _MAX_NAME_BYTES:
        raise refuse(f"is too long for a folder name ({len(encoded)} bytes, at most {_MAX_NAME_BYTES})")
    if name.casefold() == SUMMARY_NAME:
        raise refuse(f"is the name of the summary ({SUMMARY_NAME})")
    if name.casefold() in taken:
        raise refuse(f"is taken by pair {taken[name.casefold()]} (names must differ, also in case)")


def run_pair(pair: dict[str, Any], out: Path, options: dict[str, Any]) -> dict[str, Any]:
    """One pair, its failure turned into a record (runs in a worker process or on a Dask worker)."""
    from ursim_core.cli.match import match_pair

    record: dict[str, Any] = {"name": pair["name"], "sketch": str(pair["sketch"]), "metric": str(pair["metric"])}
    try:
        result = match_pair(
            pair["sketch"],
            pair["metric"],
            out / pair["name"],
            options,
            reference_path=pair["reference"],
            review_path=pair.get("review"),
        )
    except UrsimError as error:
        return {**record, "status": "failed", "error": str(error)}
    except OSError as error:
        from ursim_core.cli.main import os_error_text

        return {**record, "status": "failed", "error": os_error_text(error)}
    result.pop("out", None)
    # How the sketch was read and how close the runner-up came: sorted by the gap, a campaign's
    # close calls come first (see ursim_core.matching.orientation.next_reading).
    degrees, mirrored = result.pop("orientation")
    runner_up = result.pop("next_reading", None)
    result.update(
        orientation_degrees=float(degrees),
        orientation_mirrored=bool(mirrored),
        next_reading_gap=float(runner_up["ranked_worse_by"]) if runner_up else "",
        # The laid sketch's pairs (MatchConfig.elastic) or the matcher's own.
        pairs_from="laid sketch" if result.pop("laid", False) else "matcher",
    )
    return {**record, **result, "status": "ok", "error": ""}


def _summary_csv(records: list[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(SUMMARY_COLUMNS)
    for record in records:
        row = []
        for column in SUMMARY_COLUMNS:
            value = record.get(column, "")
            if isinstance(value, float):
                value = "" if value != value else format(value, ".6g")
            row.append(value)
        writer.writerow(row)
    return buffer.getvalue()


def _run_local(pairs, out, options, workers, progress):
    import functools

    from ursim_core.evaluation.pool import completed

    # The evaluation's pool: pairs in order on one worker, else processes that are each told
    # their share of the CPUs (a turned sketch's resamplings are segmented on threads).
    function = functools.partial(run_pair, out=out, options=options)
    for index, (_, record) in enumerate(completed(function, pairs, workers=workers), start=1):
        progress(index, text=record["name"])
        yield record


def _run_dask(pairs, out, options, scheduler, progress):
    from distributed import as_completed

    from ursim_core.evaluation.distributed import connect

    client = connect(scheduler)
    try:
        futures = [client.submit(run_pair, pair, out, options, pure=False) for pair in pairs]
        for index, future in enumerate(as_completed(futures), start=1):
            record = future.result()
            progress(index, text=record["name"])
            yield record
    finally:
        client.close()


def check_options(options: dict[str, Any]) -> None:
    """Refuse, before any pair runs, options every pair would fail on: ``--m``, ``--set``, the
    presets, ``--param``, ``--threshold``, ``--max-pixels`` (:class:`~ursim_core.errors.ParameterError`)."""
    from types import SimpleNamespace

    from ursim_core.cli.common import check_map_options, segmentation_params
    from ursim_core.cli.match_options import match_config
    from ursim_core.segmentation import resolve_params

    args = SimpleNamespace(**options)
    match_config(args).resolved()
    params = segmentation_params(args)
    for option, preset in (("--sketch-preset", args.sketch_preset), ("--metric-preset", args.metric_preset)):
        try:
            resolve_params("maoris", preset, params)
        except ParameterError as error:
            if error.field:  # a --param value, named by the error itself
                raise
            raise ParameterError(f"{option}: {error.problem}") from None
    check_map_options(args)


def _encoded(text: str) -> bytes:
    # A path from a JSON manifest may hold the undecodable bytes of a file name (as os.fsdecode
    # keeps them): written back as those bytes, any other lone surrogate escaped.
    try:
        return text.encode("utf-8", "surrogateescape")
    except UnicodeEncodeError:
        return text.encode("utf-8", "backslashreplace")


def run(args: argparse.Namespace) -> int:
    from ursim_core.cli.match_options import options_of
    from ursim_core.io.atomic import atomic_write_bytes

    out = check_output_folder(args.output)
    pairs = read_manifest(args.manifest)
    options = options_of(args)
    check_options(options)
    progress = progress_bar(len(pairs), "match-batch")
    out.mkdir(parents=True, exist_ok=True)
    if args.scheduler:
        records = list(_run_dask(pairs, out, options, args.scheduler, progress))
    else:
        records = list(_run_local(pairs, out, options, max(1, args.workers), progress))
    order = {pair["name"]: index for index, pair in enumerate(pairs)}
    records.sort(key=lambda record: order[record["name"]])
    atomic_write_bytes(out / SUMMARY_NAME, _encoded(_summary_csv(records)))
    failed = [record for record in records if record["status"] != "ok"]
    for record in failed:
        print(f"error: {record['name']}: {record['error']}", file=sys.stderr)
    print(f"{len(records) - len(failed)} of {len(records)} pairs matched; wrote {out / SUMMARY_NAME}")
    return 1 if failed else 0
