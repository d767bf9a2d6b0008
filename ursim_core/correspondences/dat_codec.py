"""The original annotators' ``.dat`` format (points only), kept for the published ground truth.

Read with :func:`load_dat`, written with :func:`save_dat`.
"""

from __future__ import annotations

import hashlib
import os
import re
import urllib.parse
from pathlib import Path, PurePosixPath

from ursim_core.correspondences.files import paused_garbage_collection, read_file_bytes, write_guarded
from ursim_core.correspondences.values import Clique, Correspondences, MapRef
from ursim_core.errors import FormatError

__all__ = ["load_dat", "save_dat"]


_DAT_SET = re.compile(r"^#\s*(\d+)\s*match set$")
_DAT_SIDE = re.compile(r"^#\s*map([12])$")
_DAT_POINT = re.compile(r"^(\d+)\s+(\d+)$")
# A pixel coordinate has a handful of digits; Python refuses int() of more than 4300.
_MAX_DIGITS = 18
_DAT_NO_PATH = "-"


def load_dat(path: str | os.PathLike, *, drop_empty: bool = False) -> Correspondences:
    """Read a ground-truth file in the original annotators' ``.dat`` format.

    The layout is a header ``# <map1 path> <map2 path>`` then match sets, each
    ``# Kmatch set``, ``# map1``, ``ROW COL`` lines, ``# map2``, ``ROW COL`` lines;
    blank lines are ignored. map1 is the sketch, map2 the metric map. Clique ids
    are 1, 2, ... in file order (the ``K`` numbers are not kept). The header's
    paths are kept as written: in ``MapRef.path`` (not resolved; ``-`` means
    none) and verbatim in ``MapRef.extra["dat_path"]``.

    Parameters
    ----------
    path : str or path-like
        The ``.dat`` file.
    drop_empty : bool, optional
        Drop match sets without any point. False by default because the legacy
        scorer counts the trailing empty set of the published files.

    Returns
    -------
    Correspondences
        Cliques with points only (``source="manual"``); fill the regions with
        :func:`assign_regions`.

    Raises
    ------
    FormatError
        Missing or unreadable file, or a malformed line (the message gives its number).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "gt.dat"
    >>> _ = target.write_text("# a.png b.png\\n# 0match set\\n# map1\\n228 302\\n# map2\\n166 308\\n\\n")
    >>> corr = load_dat(target)
    >>> corr.sketch.path.name, corr.cliques[0].sketch_points, corr.cliques[0].metric_points
    ('a.png', ((228, 302),), ((166, 308),))
    """
    path = Path(path)
    raw = read_file_bytes(path, what=".dat file")
    with paused_garbage_collection():
        return _parse_dat(raw, path, drop_empty=drop_empty)


def _parse_dat(raw: bytes, path: Path, *, drop_empty: bool) -> Correspondences:
    lines = _dat_lines(raw, path)
    if not lines:
        raise FormatError("empty file; expected a '# <map1 path> <map2 path>' header", path=path)
    sketch_ref, metric_ref = _parse_dat_header(lines[0], path)

    sets: list[dict] = []
    current: dict | None = None
    for number, text_line in enumerate(lines[1:], start=2):
        line = text_line.strip()
        if not line:
            continue
        point = _DAT_POINT.match(line)
        if point:
            if current is None or current["side"] is None:
                raise FormatError(f"line {number}: point {line!r} before '# map1' or '# map2'", path=path)
            row, col = point.groups()
            if len(row) > _MAX_DIGITS or len(col) > _MAX_DIGITS:
                digits = max(len(row), len(col))
                raise FormatError(
                    f"line {number}: a number of {digits} digits is too large for a pixel coordinate", path=path
                )
            current["points"][current["side"]].append((int(row), int(col)))
            continue
        if _DAT_SET.match(line):
            _finish_dat_set(current, number, path)
            current = {"line": number, "side": None, "points": {"1": [], "2": []}}
            sets.append(current)
            continue
        side = _DAT_SIDE.match(line)
        if side:
            if current is None:
                raise FormatError(f"line {number}: {line!r} before the first '# Kmatch set' line", path=path)
            if current["side"] == "2":
                raise FormatError(f"line {number}: {line!r} after '# map2' in the same match set", path=path)
            expected = "1" if current["side"] is None else "2"
            if side.group(1) != expected:
                raise FormatError(f"line {number}: expected '# map{expected}', got {line!r}", path=path)
            current["side"] = expected
            continue
        raise FormatError(
            f"line {number}: expected 'ROW COL' (two non-negative integers), '# Kmatch set', "
            f"'# map1' or '# map2', got {text_line.strip()!r}",
            path=path,
        )
    _finish_dat_set(current, len(lines) + 1, path)

    cliques = []
    for match_set in sets:
        sketch_points, metric_points = match_set["points"]["1"], match_set["points"]["2"]
        if drop_empty and not sketch_points and not metric_points:
            continue
        # The line patterns admit only pairs of non-negative integers: nothing left to check.
        cliques.append(
            Clique._trusted(
                id=len(cliques) + 1,
                sketch_points=tuple(sketch_points),
                metric_points=tuple(metric_points),
                sketch_regions=(),
                metric_regions=(),
                source="manual",
                score=None,
                note="",
                status=None,
                extra={},
            )
        )
    return Correspondences(
        sketch=sketch_ref, metric=metric_ref, cliques=tuple(cliques), loaded_sha256=hashlib.sha256(raw).hexdigest()
    )


def save_dat(corr: Correspondences, path: str | os.PathLike, *, expected_sha256: str | None = None) -> str:
    """Write ``corr`` in the original annotators' ``.dat`` format, atomically.

    Only points are written (the format has nothing else); match sets are
    numbered 0, 1, ... in clique order and each is followed by a blank line, as
    in the published files. Header paths are ``MapRef.extra["dat_path"]`` when it
    still names ``MapRef.path``, else the path itself, ``-`` for none;
    white space and ``%`` inside a path are %-escaped so the two-token header
    stays readable (:func:`load_dat` decodes them).

    Parameters
    ----------
    corr : Correspondences
        What to write.
    path : str or path-like
        Destination ``.dat`` file.
    expected_sha256 : str, optional
        The digest the file had when loaded (``corr.loaded_sha256``): refuse to overwrite it
        if it changed on disk since.

    Returns
    -------
    str
        SHA-256 of the bytes written.

    Raises
    ------
    FileChangedError
        ``expected_sha256`` was given and the file now holds other bytes.
    SaveRefusedError
        ``path`` is one of the maps (or label images) of ``corr``.
    FormatError
        A map path cannot be written in the header, or a point has a coordinate too large
        for the format (more than 18 digits: :func:`load_dat` would refuse it).
    OSError
        Writing failed; an existing file is left unchanged.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> target = pathlib.Path(tempfile.mkdtemp()) / "gt.dat"
    >>> corr = Correspondences(MapRef(path="a.png"), MapRef(path="b.png"),
    ...                        cliques=(Clique(id=1, sketch_points=[(1, 2)], metric_points=[(3, 4)]),))
    >>> digest = save_dat(corr, target)
    >>> print(target.read_text(), end="")
    # a.png b.png
    # 0match set
    # map1
    1 2
    # map2
    3 4
    <BLANKLINE>
    """
    path = Path(path)
    lines = [f"# {_dat_header_token(corr.sketch, path)} {_dat_header_token(corr.metric, path)}"]
    for index, clique in enumerate(corr.cliques):
        _check_readable_points(clique, index, path)
        lines.append(f"# {index}match set")
        lines.append("# map1")
        lines.extend(f"{row} {col}" for row, col in clique.sketch_points)
        lines.append("# map2")
        lines.extend(f"{row} {col}" for row, col in clique.metric_points)
        lines.append("")
    data = ("\n".join(lines) + "\n").encode("utf-8")
    return write_guarded(corr, path, data, expected_sha256=expected_sha256, what=".dat file")


def _check_readable_points(clique: Clique, index: int, path: Path) -> None:
    """Refuse a point :func:`load_dat` would refuse to read back (a coordinate of more than
    ``_MAX_DIGITS`` digits): a file that saves must load."""
    limit = 10**_MAX_DIGITS
    for side in ("sketch_points", "metric_points"):
        for number, point in enumerate(getattr(clique, side)):
            if any(value >= limit for value in point):
                raise FormatError(
                    f"clique {clique.id}: the point {point} has a coordinate of more than {_MAX_DIGITS} digits, "
                    "which a .dat file cannot hold (it would not read back); nothing was written",
                    path=path,
                    field=f"cliques[{index}].{side}[{number}]",
                )


def _dat_lines(raw: bytes, path: Path) -> list[str]:
    try:
        # A leading byte-order mark (Notepad's "UTF-8") is dropped, as the JSON reader does.
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = raw[: error.start].count(b"\n") + 1
        raise FormatError(f"line {line}: not text (undecodable byte); not a .dat file", path=path) from None
    return text.splitlines()


def _parse_dat_header(line: str, path: Path) -> tuple[MapRef, MapRef]:
    tokens = line.strip().lstrip("#").split() if line.strip().startswith("#") else None
    if tokens is None or len(tokens) != 2:
        raise FormatError(f"line 1: expected '# <map1 path> <map2 path>', got {_cut(line.strip())!r}", path=path)
    refs = []
    for token in tokens:
        if token == _DAT_NO_PATH:
            refs.append(MapRef())
            continue
        # %XX escapes of bytes that are not UTF-8 come back as the same bytes (surrogateescape).
        text = urllib.parse.unquote(token, errors="surrogateescape")
        if "\x00" in text:
            raise FormatError(f"line 1: a map path contains a NUL character: {_cut(token)!r}", path=path)
        refs.append(MapRef(path=Path(text), extra={"dat_path": text}))
    return refs[0], refs[1]


def _cut(text: str, limit: int = 80) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _finish_dat_set(current: dict | None, number: int, path: Path) -> None:
    if current is not None and current["side"] != "2":
        missing = "'# map1' and '# map2'" if current["side"] is None else "'# map2'"
        raise FormatError(
            f"line {number}: the match set started on line {current['line']} has no {missing} line", path=path
        )


def _dat_header_token(ref: MapRef, target: Path) -> str:
    if ref.path is None:
        return _DAT_NO_PATH
    written = ref.extra.get("dat_path")
    if isinstance(written, str) and _still_names(written, ref.path):
        text = written
    else:
        text = ref.path.as_posix()
    if text == _DAT_NO_PATH:
        return "%2D"  # a file really named "-", not to be read back as "no path"
    # Escape only what breaks the header (white space, %) or is not UTF-8, so ordinary paths
    # stay readable and every path reads back as the same bytes.
    return "".join(_escaped(char, target) for char in text)


def _escaped(char: str, target: Path) -> str:
    if char.isspace() or char == "%":
        return urllib.parse.quote(char, safe="")
    if "\udc80" <= char <= "\udcff":
        # A byte of a file name that is not UTF-8, as os.fsdecode keeps it.
        return f"%{ord(char) - 0xDC00:02X}"
    if "\ud800" <= char <= "\udfff":
        raise FormatError(f"a map path holds a lone surrogate {char!r}: it is no file name", path=target)
    return char


def _still_names(written: str, path: Path) -> bool:
    """Whether the header path ``written`` still names ``path``.

    A .dat header path is relative to a folder nobody recorded (the published files name
    ``../../../../Test/...``), so after a trip through JSON, which resolves paths, the map is
    still the same when the resolved path ends with the written one.
    """
    if Path(written) == path:
        return True
    tail = [part for part in PurePosixPath(written).parts if part not in ("..", ".", "/")]
    return bool(tail) and list(path.parts[-len(tail) :]) == tail
