"""What the subcommands share: usage errors, map options, progress bars, staged output folders.

Nothing heavy is imported at module level: ``ursim --help`` imports this module.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from ursim_core.errors import ParameterError

__all__ = [
    "UsageError",
    "keep_freed_memory",
    "parse_param",
    "segmentation_params",
    "add_map_options",
    "load",
    "progress_bar",
    "announce_kernel_compilation",
    "check_output_folder",
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


@contextlib.contextmanager
def staged_folder(out: Path) -> Iterator[Path]:
    """A temporary folder beside ``out`` whose files are moved into ``out`` when the block succeeds.

    On an error (a full disk, an interruption) the temporary folder is removed and ``out`` is left
    as it was, so a run never leaves half of its outputs. Files are moved one by one with
    ``os.replace`` (atomic on one file system), so each output in ``out`` is whole, and ``out``
    is synced once after the moves (the staging folder's own syncs are skipped: see
    :func:`ursim_core.io.atomic.scratch_directory`).
    """
    from ursim_core.io.atomic import scratch_directory, sync_directory

    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
    try:
        # The staged files' contents are synced as they are saved; their names are made
        # durable once, where they end up, not in the staging folder, which is removed.
        with scratch_directory(staging):
            yield staging
        out.mkdir(exist_ok=True)
        for item in sorted(staging.iterdir()):
            os.replace(item, out / item.name)
        sync_directory(out)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


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
