"""The MAORIS kernels as the steps call them: built ahead of time when fresh, else numba's JIT.

:func:`kernels` gives one namespace with every kernel called from Python (the names of
:data:`ENTRY_KERNELS`). It is the extension modules that
:func:`build_ahead` wrote (``make`` builds them)
when they were built from the kernel sources of this install, which takes milliseconds
and no numba. When there are none, the first call builds them (about 17 s on two CPUs, once, half
the JIT's own first compile); when that fails (pycc needs a C compiler), numba's JIT
dispatchers of :mod:`.kernels`, which import numba and load (or compile) their cache. Both run the same compiled Python source for the same
signatures; a test checks that their label images agree.

``URSIM_KERNELS`` chooses: ``auto`` (default), ``jit`` (always the JIT) or ``ahead`` (the
built module, or a :class:`~ursim_core.errors.SegmentationError` saying how to build it).
This module imports neither numba nor the kernels, but to build.

The build: numba's JIT costs every new process about a second before the first segmentation,
importing numba and its typing registries (0.4-0.6 s) and loading the cached machine code of
each kernel (0.3-0.7 s). The same kernels, compiled once with :mod:`numba.pycc` for the one
signature each has (:data:`.kernels.signatures.SIGNATURES`), form ordinary extension modules
that import in milliseconds and need neither numba nor llvmlite at run time: two of them
(:data:`PARTS`), each compiled in a process of its own at the same time
(:mod:`.ahead_build`), as numba compiles on one thread. Every exported
kernel releases the GIL, as the JIT's ``count_contacts`` does (``nogil=True``): the contacts of
large maps are counted in bands on threads. The kernels touch only the arrays they are given,
never a Python object, so releasing it is safe for all of them.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from types import SimpleNamespace

from ursim_core.errors import SegmentationError

__all__ = [
    "ENTRY_KERNELS",
    "PARTS",
    "MODULE_NAME",
    "DIGEST_NAME",
    "kernels",
    "ahead_module_path",
    "build_directories",
    "sources_digest",
    "build_ahead",
    "build_or_warn",
    "forget",
]

#: The kernels called from Python, by module of :mod:`.kernels` (the helpers they call are
#: compiled into them). A test checks this against :data:`.kernels.signatures.SIGNATURES`.
ENTRY_KERNELS: dict[str, tuple[str, ...]] = {
    "discs": ("centre_rectangles", "paint_discs"),
    "flat_zones": ("label_flat_zones", "zone_values_and_sizes", "first_pixels", "resolve_parents", "relabel"),
    "adjacency": (
        "build_adjacency",
        "adjacency_entries",
        "_link_entries",
        "remove_small_zones",
        "compact_graph",
        "expand_graph",
    ),
    "contacts": ("_compact_labels", "count_contacts", "join_counts", "group_candidates", "contact_table"),
    "fusion": ("merge_ripples", "remove_doors"),
    "flooding": ("flood_levels", "clearance_levels"),
}

#: The extension modules built ahead of time, each with the kernels of these modules of
#: :mod:`.kernels`: two parts of about equal compile time (measured: 13-14 s of CPU each),
#: built in two processes at once. The helpers the two share are compiled in both.
PARTS: dict[str, tuple[str, ...]] = {
    "_maoris_kernels_a": ("fusion", "contacts"),
    "_maoris_kernels_b": ("discs", "flat_zones", "adjacency", "flooding"),
}
MODULE_NAME = "_maoris_kernels_a"
"""Name of the first of :data:`PARTS` (:func:`ahead_module_path` gives its path)."""
DIGEST_NAME = "_maoris_kernels.digest"
"""The file beside them that names the sources they were built from (:func:`sources_digest`)."""

_KERNELS_DIR = Path(__file__).resolve().parent / "kernels"
_loaded: SimpleNamespace | None = None


def sources_digest() -> str:
    """SHA-256 of the kernel sources (every ``.py`` of :mod:`.kernels`), of how they are built
    (:mod:`.ahead_build`) and of the Python ABI.

    The built modules are used only while this matches the digest they were built with: an
    edited kernel falls back to the JIT until the modules are built again.
    """
    digest = hashlib.sha256(importlib.machinery.EXTENSION_SUFFIXES[0].encode())
    for source in [*sorted(_KERNELS_DIR.glob("*.py")), _KERNELS_DIR.parent / "ahead_build.py"]:
        digest.update(source.name.encode() + b"\0" + source.read_bytes() + b"\0")
    return digest.hexdigest()


def build_directories() -> list[Path]:
    """Where the built module may live, in the order looked at: beside the kernels (a
    checkout or a writable install), then the user's cache (``$XDG_CACHE_HOME/ursim``)."""
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    folder = hashlib.sha1(str(_KERNELS_DIR).encode()).hexdigest()[:16]
    own = _KERNELS_DIR / "__pycache__"
    user = Path(xdg) / "ursim" / f"kernels-{folder}"
    return [own, user] if os.access(_KERNELS_DIR, os.W_OK) else [user, own]


def _part_path(folder: Path, name: str) -> Path:
    return folder / (name + importlib.machinery.EXTENSION_SUFFIXES[0])


def ahead_module_path() -> Path | None:
    """The first built module (:data:`MODULE_NAME`) of these kernel sources, or None when
    any of :data:`PARTS` is missing or they are stale."""
    wanted = None
    for folder in build_directories():
        try:
            recorded = (folder / DIGEST_NAME).read_text(encoding="ascii").strip()
        except OSError:
            continue
        wanted = wanted or sources_digest()
        if recorded == wanted and all(_part_path(folder, name).is_file() for name in PARTS):
            return _part_path(folder, MODULE_NAME)
    return None


def _load_ahead(path: Path) -> SimpleNamespace:
    """Every kernel, from the parts beside ``path`` (:func:`ahead_module_path`)."""
    found = {}
    for name, modules in PARTS.items():
        spec = importlib.util.spec_from_file_location(name, _part_path(path.parent, name))
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        found.update({kernel: getattr(module, kernel) for group in modules for kernel in ENTRY_KERNELS[group]})
    return SimpleNamespace(source="ahead", path=path, **found)


def _load_jit() -> SimpleNamespace:
    import importlib

    found = {}
    for module_name, names in ENTRY_KERNELS.items():
        module = importlib.import_module(f"ursim_core.segmentation.maoris.kernels.{module_name}")
        found.update({name: getattr(module, name) for name in names})
    return SimpleNamespace(source="jit", path=None, **found)


def kernels() -> SimpleNamespace:
    """Every kernel called from Python, and ``source`` ("ahead" or "jit"); loaded once.

    Examples
    --------
    >>> kernels().source in ("ahead", "jit")
    True
    """
    global _loaded
    if _loaded is None:
        choice = os.environ.get("URSIM_KERNELS", "auto").strip().lower() or "auto"
        if choice not in ("auto", "jit", "ahead"):
            raise SegmentationError(f"URSIM_KERNELS must be auto, jit or ahead, not {choice!r}")
        path = None if choice == "jit" else ahead_module_path()
        if choice == "auto" and path is None:
            path = build_or_warn()  # once per install: as long as the JIT's first compile
        if choice == "ahead" and path is None:
            raise SegmentationError(
                "URSIM_KERNELS=ahead but the kernels are not built for these sources: run "
                f"`{Path(sys.executable).name} -m ursim_core.segmentation.maoris.compiled`"
            )
        _loaded = _load_ahead_or_warn(path, choice) if path is not None else None
        if _loaded is None:
            _loaded = _load_jit()
    return _loaded


def _load_ahead_or_warn(path: Path, choice: str) -> SimpleNamespace | None:
    """The built module at ``path``; a broken one (truncated, foreign, missing a kernel) is
    reported, and then built again (``auto``), refused (``ahead``) or left for the JIT."""
    try:
        return _load_ahead(path)
    except (ImportError, OSError, AttributeError) as error:
        problem = f"the segmentation kernels built at {path} cannot be loaded ({type(error).__name__}: {error})"
    if choice == "ahead":
        raise SegmentationError(problem)
    warnings.warn(f"{problem}; building them again", RuntimeWarning, stacklevel=3)
    rebuilt = build_or_warn()
    if rebuilt is None:
        return None
    try:
        return _load_ahead(rebuilt)
    except (ImportError, OSError, AttributeError):
        return None


def build_or_warn() -> Path | None:
    """Build the kernels ahead of time; on failure warn, and return None (the JIT is used)."""
    try:
        return build_ahead()
    except Exception as error:
        warnings.warn(
            f"could not build the segmentation kernels ahead of time ({type(error).__name__}: {error}); "
            "using numba's JIT, which starts about a second slower",
            RuntimeWarning,
            stacklevel=2,
        )
        return None


def forget() -> None:
    """Load again on the next :func:`kernels` (after a build, or to switch ``URSIM_KERNELS``)."""
    global _loaded
    _loaded = None


def build_ahead(directory: str | Path | None = None) -> Path:
    """Compile every kernel into the extension modules loaded here; return the first's path.

    Each of :data:`PARTS` is compiled by a process of its own (:mod:`.ahead_build`), all at
    once. The modules and their digest file are written to ``directory`` (default: the first
    writable of :func:`build_directories`): the old digest is removed first, then each module
    and the new digest are put in place by a rename, so a reader never sees a digest without
    its modules. Takes about 17 s on two CPUs (``ursim bench compile`` measures it).

    Raises
    ------
    RuntimeError
        When a part fails to build (with the end of its error output).
    """
    target = Path(directory) if directory is not None else build_directories()[0]
    target.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="ursim-kernels-", dir=target) as scratch:
        _build_parts(scratch)
        (target / DIGEST_NAME).unlink(missing_ok=True)
        for name in PARTS:
            os.replace(_part_path(Path(scratch), name), _part_path(target, name))
        digest_path = Path(scratch) / "digest"
        digest_path.write_text(sources_digest() + "\n", encoding="ascii")
        os.replace(digest_path, target / DIGEST_NAME)
    forget()
    return _part_path(target, MODULE_NAME)


def _build_parts(scratch: str) -> None:
    """Run :mod:`.ahead_build` for every part at once, each writing its module to ``scratch``."""
    # The children import this very package (first on their path), whatever their working
    # folder holds: they run in the scratch folder.
    package_root = str(Path(__file__).resolve().parents[3])
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [package_root, os.environ.get("PYTHONPATH")]))}
    children = []
    for name in PARTS:
        command = [sys.executable, "-m", "ursim_core.segmentation.maoris.ahead_build", name, scratch]
        # Each child's errors go to a file: a pipe left unread could fill and block it.
        log = open(Path(scratch) / f"{name}.log", "w+b")  # noqa: SIM115 (closed below)
        child = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, cwd=scratch, env=env)
        children.append((name, child, log))
    failures = []
    for name, child, log in children:
        code = child.wait()
        log.seek(0)
        output = log.read().decode(errors="replace").strip()
        log.close()
        if code != 0 or not _part_path(Path(scratch), name).is_file():
            failures.append(f"{name} (exit {code}): {output[-800:]}")
    if failures:
        raise RuntimeError("building the kernels failed: " + "; ".join(failures))


def _main() -> None:  # ``python -m ursim_core.segmentation.maoris.compiled``
    started = time.perf_counter()
    path = build_ahead()
    print(f"{path} ({time.perf_counter() - started:.1f} s)")


if __name__ == "__main__":
    _main()
