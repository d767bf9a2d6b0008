"""What the subcommands share: usage errors, map options, progress bars, staged output folders.

Nothing heavy is imported at module level: ``ursim --help`` imports this module.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import re
import shutil
import stat
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from ursim_core.errors import ParameterError, SaveRefusedError

__all__ = [
    "UsageError",
    "keep_freed_memory",
    "parse_param",
    "segmentation_params",
    "add_map_options",
    "check_map_options",
    "load",
    "progress_bar",
    "announce_kernel_compilation",
    "check_output_folder",
    "finite_or_nan",
    "check_output_files",
    "refuse_overwriting_inputs",
    "staged_folder",
]


class UsageError(ParameterError):
    """A command line that cannot be run as given (missing argument, conflicting options): exit 2."""


def parse_param(text: str) -> tuple[str, Any]:
    """``NAME=VALUE`` of ``--param``, the value converted to int, float or bool when it reads as one.

    Examples
    --------
    >>> parse_param("threshold=0.4"), parse_param("fill=true"), parse_param("name=a=b")
    (('threshold', 0.4), ('fill', True), ('name', 'a=b'))
    """
    if "=" not in text:
        raise UsageError(f"--param expects NAME=VALUE, got '{text}'")
    name, raw = text.split("=", 1)
    value: Any = raw
    for convert in (int, float):
        try:
            value = convert(raw)
            break
        except ValueError:
            continue
    if raw.lower() in ("true", "false"):
        value = raw.lower() == "true"
    return name.strip(), value


def segmentation_params(args: argparse.Namespace) -> dict[str, Any]:
    return dict(parse_param(p) for p in args.param or [])


def add_map_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("map loading")
    group.add_argument(
        "--threshold", type=int, default=250, help="grey value above which a pixel is free (default 250)"
    )
    group.add_argument(
        "--nonzero-free",
        action="store_true",
        help="every non-zero pixel is free (the released URSIM driver's behaviour)",
    )
    group.add_argument(
        "--max-pixels", type=int, default=64_000_000, help="refuse maps larger than this (default 64 Mpx)"
    )


def check_map_options(args: argparse.Namespace) -> None:
    """Refuse, before any work, a ``--threshold`` outside 0..255 or a ``--max-pixels`` below 1.

    The rules are the map loader's (:func:`ursim_core.io.maps.check_threshold`,
    :func:`~ursim_core.io.maps.check_max_pixels`); the message names the option.

    Raises
    ------
    ParameterError
        For example ``--threshold must be a number in 0..255, got 300``.
    """
    from ursim_core.io.maps import check_max_pixels, check_threshold

    check_threshold(args.threshold, option="--threshold")
    check_max_pixels(args.max_pixels, option="--max-pixels")


def load(path: str | Path, args: argparse.Namespace):
    """Load a map with the map-loading options of ``args`` (a map with no free pixel is refused
    by :func:`ursim_core.io.maps.load_map`)."""
    from ursim_core.io.maps import load_map

    return load_map(path, threshold=args.threshold, nonzero_free=args.nonzero_free, max_pixels=args.max_pixels)


def progress_bar(total: int, label: str) -> Callable[..., None]:
    """A tqdm progress bar on stderr as a ``(done, total, text)`` callback; silent when not a terminal.

    Calling it with ``done >= total`` closes the bar.
    """
    isatty = getattr(sys.stderr, "isatty", None)
    if isatty is not None and not isatty():
        # tqdm's disable=None would draw nothing here: skip importing it (about 20 ms, with
        # importlib.metadata and multiprocessing's locks) for a bar nobody sees.
        return _silent_progress()
    from tqdm import tqdm

    bar = tqdm(total=max(total, 1), desc=label, unit="step", file=sys.stderr, disable=None, leave=False)

    def update(done: int, new_total: int | None = None, text: str = "") -> None:
        if new_total is not None and new_total != bar.total:
            bar.total = max(new_total, 1)
        bar.update(max(0, done - bar.n))
        if text:
            bar.set_postfix_str(text[:40], refresh=False)
        if done >= bar.total:
            bar.close()

    update.close = bar.close  # type: ignore[attr-defined]
    return update


def _silent_progress() -> Callable[..., None]:
    """The callback of :func:`progress_bar` when stderr is not a terminal: does nothing."""

    def update(done: int, new_total: int | None = None, text: str = "") -> None:
        return None

    update.close = lambda: None  # type: ignore[attr-defined]
    return update


_announced = False


def announce_kernel_compilation() -> None:
    """Before the first segmentation of the process: say on stderr when the kernels must be compiled."""
    global _announced
    if _announced:
        return
    _announced = True
    from ursim_core.segmentation.maoris import compile_notice

    notice = compile_notice()
    if notice:
        print(notice, file=sys.stderr, flush=True)


def finite_or_nan(text: str) -> float:
    """``float(text)``, or NaN when it is not a number or not finite (NaN, infinity, ``1e400``): the
    argparse types that want a finite number test the one value.

    >>> finite_or_nan("2.5"), finite_or_nan("inf"), finite_or_nan("x")
    (2.5, nan, nan)
    """
    import math

    try:
        value = float(text)
    except ValueError:
        return math.nan
    return value if math.isfinite(value) else math.nan


def check_output_folder(path: str | Path, option: str = "-o") -> Path:
    """Refuse, before any work, an output folder that is a file or cannot be created or written."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"{option} must be a folder, but this is a file", path=folder)
    existing = folder
    while not existing.exists():
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise ParameterError(f"cannot create the folder: {existing} is a file", path=folder)
    if existing.exists() and not os.access(existing, os.W_OK | os.X_OK):
        raise ParameterError("cannot write here (permission denied)", path=existing)
    return folder


def _same_file(first: Path, second: Path) -> bool:
    """Whether two paths name one file: the same inode when both exist (hard links, symbolic
    links, a case-insensitive file system), else the same resolved path."""
    try:
        return os.path.samefile(first, second)
    except (OSError, ValueError):
        pass
    try:
        return os.path.normcase(os.path.realpath(first)) == os.path.normcase(os.path.realpath(second))
    except (OSError, ValueError):
        return False


def refuse_overwriting_inputs(
    outputs: Iterable[str | os.PathLike | None],
    inputs: Iterable[str | os.PathLike | tuple[str | os.PathLike, str] | None],
) -> None:
    """Refuse, before any work, an output that is one of the command's input files, or another output.

    ``ursim goal sketch.png map.yaml --at 1,2 -o sketch.png`` would otherwise turn the sketch
    into JSON, and ``-o a.json --waypoints a.json`` keep only the second file. The rule of the
    correspondence savers (which refuse to write onto the maps they refer to), for every
    command that writes files. ``None`` entries (options not given) are skipped.

    Parameters
    ----------
    outputs : iterable of path or None
        The files the command will write.
    inputs : iterable of path, (path, why) or None
        The files it reads: its arguments, and as ``(path, why)`` those it reads because a file
        names them (:mod:`ursim_core.cli.inputs`: a YAML map's image, a correspondence file's
        label images); ``why`` is said in the message.

    Raises
    ------
    SaveRefusedError
        Naming the output and the input it would overwrite; nothing was written.

    Examples
    --------
    >>> refuse_overwriting_inputs(["out.json", None], ["sketch.png", "map.yaml"])
    >>> refuse_overwriting_inputs(["./sketch.png"], ["sketch.png"])
    Traceback (most recent call last):
    ...
    ursim_core.errors.SaveRefusedError: sketch.png: refusing to write an output onto the input sketch.png (it would be overwritten): choose another file name
    >>> refuse_overwriting_inputs(["map.pgm"], [("map.pgm", "the image map.yaml names")])
    Traceback (most recent call last):
    ...
    ursim_core.errors.SaveRefusedError: map.pgm: refusing to write an output onto the input map.pgm (the image map.yaml names; it would be overwritten): choose another file name
    """
    given_inputs = [
        (Path(item[0]), f"{item[1]}; ") if isinstance(item, tuple) else (Path(item), "")
        for item in inputs
        if item is not None
    ]
    seen: list[Path] = []
    for output in (Path(path) for path in outputs if path is not None):
        for source, why in given_inputs:
            if _same_file(output, source):
                raise SaveRefusedError(
                    f"refusing to write an output onto the input {source} ({why}it would be overwritten): "
                    "choose another file name",
                    path=output,
                )
        for earlier in seen:
            if _same_file(output, earlier):
                raise SaveRefusedError(
                    f"two outputs would be written to one file (also {earlier}): choose another file name",
                    path=output,
                )
        seen.append(output)


def _in_the_way(path: Path) -> str | None:
    """Why the output ``path`` cannot be replaced by a file, or None when it can (missing or a file)."""
    try:
        mode = os.lstat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as error:
        return f"cannot be checked ({error.strerror or error})"
    if stat.S_ISREG(mode) or stat.S_ISLNK(mode):
        return None  # os.replace swaps a file or a link for the new file
    return "is a folder" if stat.S_ISDIR(mode) else "is not a regular file (a device, pipe or socket)"


def check_output_files(out: str | os.PathLike, names: Iterable[str]) -> None:
    """Refuse, before any work, outputs ``out/NAME`` that cannot be written: a folder, a device or a
    pipe is in their place.

    Raises
    ------
    SaveRefusedError
        Naming the first such output; nothing was written.
    """
    out = Path(out)
    for name in names:
        problem = _in_the_way(out / name)
        if problem is not None:
            raise SaveRefusedError(f"{problem}, not a file: cannot write this output here", path=out / name)


@contextlib.contextmanager
def staged_folder(out: Path) -> Iterator[Path]:
    """A temporary folder beside ``out`` whose files are moved into ``out`` when the block succeeds.

    On an error (a full disk, an interruption) the temporary folder is removed and ``out`` is left
    as it was, so a run never leaves half of its outputs. Every destination is checked before the
    first move (a folder or a device in the place of an output: :class:`SaveRefusedError`, nothing
    moved); files are then moved one by one with ``os.replace`` (atomic on one file system), so
    each output in ``out`` is whole, and ``out`` is synced once after the moves (the staging
    folder's own syncs are skipped: see :func:`ursim_core.io.atomic.scratch_directory`).

    A staging folder left by a run that was killed (``.OUT.xxxxxxxx.tmp`` beside ``out``) is
    removed by the next run into ``out`` (:func:`_remove_stale_staging`).
    """
    from ursim_core.io.atomic import scratch_directory, sync_directory

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    _remove_stale_staging(out)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    lock = _hold(staging)
    try:
        # The staged files' contents are synced as they are saved; their names are made
        # durable once, where they end up, not in the staging folder, which is removed.
        try:
            with scratch_directory(staging):
                yield staging
        except OSError as error:
            _name_final_paths(error, staging, out)
            raise
        items = sorted(staging.iterdir())
        check_output_files(out, (item.name for item in items))
        out.mkdir(exist_ok=True)
        for item in items:
            os.replace(item, out / item.name)
        sync_directory(out)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
        if lock is not None:
            os.close(lock)


def _name_final_paths(error: OSError, staging: Path, out: Path) -> None:
    """Make ``error`` name the output in ``out``, not its staged copy: the user never sees the
    staging folder (e.g. ``out/matches.png: File too large``)."""
    for attribute in ("filename", "filename2"):
        name = getattr(error, attribute)
        if isinstance(name, (str, os.PathLike)):
            relative = os.path.relpath(os.fspath(name), staging)
            if relative != os.pardir and not relative.startswith(os.pardir + os.sep):
                setattr(error, attribute, os.fspath(out / relative))


def _hold(folder: Path | str) -> int | None:
    """A descriptor of ``folder`` holding an exclusive ``flock`` on it, or None when it cannot be
    taken (another process holds it, or no locks here: Windows, some network file systems).

    The lock marks a staging folder as in use: the system drops it when its process dies, however
    it dies, so a folder whose lock can be taken belongs to no running ``ursim``.
    """
    try:
        import fcntl
    except ImportError:
        return None
    try:
        descriptor = os.open(folder, os.O_RDONLY)
    except OSError:
        return None
    try:
        fcntl.flock(descriptor, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(descriptor)
        return None
    return descriptor


def _remove_stale_staging(out: Path) -> None:
    """Remove the staging folders of ``out`` that killed runs left (see :func:`staged_folder`).

    Only folders of the exact name ``tempfile.mkdtemp`` gives them (``.OUT.`` + 8 characters +
    ``.tmp``), untouched for :data:`~ursim_core.io.atomic.STALE_TEMP_SECONDS` and whose lock can
    be taken (no live run holds it; a run of an older version, which took no lock, would have
    touched its folder within that time unless it was long dead). Cleaning is a courtesy: any
    problem leaves the folder.
    """
    from ursim_core.io.atomic import STALE_TEMP_SECONDS

    pattern = re.compile(re.escape(f".{out.name}.") + r"[a-z0-9_]{8}\.tmp\Z")
    deadline = time.time() - STALE_TEMP_SECONDS
    try:
        entries = [entry for entry in os.scandir(out.parent) if pattern.match(entry.name)]
    except OSError:
        return
    for entry in entries:
        try:
            if not entry.is_dir(follow_symlinks=False) or entry.stat(follow_symlinks=False).st_mtime >= deadline:
                continue
        except OSError:
            continue
        lock = _hold(entry.path)
        if lock is None:
            continue
        try:
            shutil.rmtree(entry.path, ignore_errors=True)
        finally:
            os.close(lock)


def add_subcommand(subparsers, name: str, module) -> argparse.ArgumentParser:
    """Add the subcommand ``name`` of ``module`` (``HELP``, ``EXAMPLES``, ``configure``, ``run``) to
    ``subparsers`` on its own, outside the ``ursim`` parser (for embedding and tests); ``handler`` runs it."""
    parser = subparsers.add_parser(
        name,
        help=module.HELP,
        description=module.HELP,
        epilog=module.EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    module.configure(parser)
    parser.set_defaults(handler=module.run)
    return parser


#: glibc's mallopt parameters (malloc.h) and the value :func:`keep_freed_memory` gives them.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD, _KEEP_BYTES = -1, -3, 1 << 30


def keep_freed_memory() -> None:
    """Let glibc reuse freed memory instead of handing it back and faulting it in again.

    By default, blocks above a threshold (32 MB at most) are mapped and unmapped on every
    allocation, and free memory at the top of the heap is returned to the system: a
    building-sized pair allocates and frees arrays of 10-300 MB over and over (masks of the c
    matrix, label and distance images), and the kernel zeroes and faults their pages in each
    time. 8000 px pair (``ursim match``, interleaved with the code before x2): 1.03-1.05 million
    minor page faults and 8.5-10.5 s of system time without, 0.72-0.75 million and 8.0-8.5 s with
    this (on a loaded machine), the peak resident size within 2 %. Memory is still given back
    after the segmentations (:func:`ursim_core.cli.match.load_and_segment` trims explicitly).
    glibc only; elsewhere nothing. ``ursim match`` calls it.
    """
    import ctypes

    try:
        libc = ctypes.CDLL(None)
        libc.mallopt(_M_MMAP_THRESHOLD, _KEEP_BYTES)
        libc.mallopt(_M_TRIM_THRESHOLD, _KEEP_BYTES)
    except (OSError, AttributeError, TypeError):
        pass
