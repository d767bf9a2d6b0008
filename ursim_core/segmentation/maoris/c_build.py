"""Compiling the MAORIS kernels in C (:file:`csrc`) into the extension module ``_maoris_kernels``.

Each source file is compiled by a process of its own (the C compiler Python was built with,
``sysconfig``'s ``CC``), as many at once as there are CPUs, then linked (``LDSHARED``).
This replaced numba's ``pycc`` build of the same kernels (deprecated by numba, and 16.6 s on
two CPUs for what the C compiler does in a few seconds).

Floating point is compiled as written (``-ffp-contract=off``: no fused multiply-adds, no
``-ffast-math``), so that the kernels compute what numba's do, bit for bit.
"""

from __future__ import annotations

import os
import shlex
import subprocess
import sysconfig
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

__all__ = ["SOURCE_DIR", "CFLAGS", "build_module", "source_files"]

SOURCE_DIR = Path(__file__).resolve().parent / "csrc"
"""Where the C sources of the kernels live."""

#: Compiler flags of every source (after Python's own ``CCSHARED``, e.g. ``-fPIC``).
CFLAGS = ("-O3", "-std=gnu11", "-pthread", "-ffp-contract=off", "-fno-strict-aliasing", "-Wall", "-Wno-unused-function")


def source_files() -> list[Path]:
    """The sources and headers the module is built from, in a stable order (for the digest)."""
    return sorted([*SOURCE_DIR.glob("*.c"), *SOURCE_DIR.glob("*.h")])


def _compiler() -> tuple[list[str], list[str]]:
    """The compile and the link command of this Python's build (``CC``, ``LDSHARED``)."""
    import numpy

    cc = shlex.split(os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc")
    shared = shlex.split(sysconfig.get_config_var("CCSHARED") or "-fPIC")
    includes = [f"-I{sysconfig.get_paths()['include']}", f"-I{numpy.get_include()}", f"-I{SOURCE_DIR}"]
    ldshared = shlex.split(os.environ.get("LDSHARED") or sysconfig.get_config_var("LDSHARED") or "cc -shared")
    return [*cc, *shared, *CFLAGS, *includes], ldshared


def _run(command: list[str], cwd: Path) -> None:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        output = (done.stderr or done.stdout).strip()
        raise RuntimeError(f"`{shlex.join(command[:2])} ...` failed (exit {done.returncode}): {output[-1500:]}")


def build_module(output: str | Path, *, jobs: int | None = None) -> Path:
    """Compile every C source of :data:`SOURCE_DIR` and link them into ``output``.

    Parameters
    ----------
    output : str or Path
        The extension module to write (its name must end in this Python's extension suffix).
    jobs : int, optional
        Compilers run at once (default: the number of CPUs).

    Returns
    -------
    Path
        ``output``.

    Raises
    ------
    RuntimeError
        When no C compiler is found, or one fails (with the end of its messages).
    """
    output = Path(output)
    compile_command, link_command = _compiler()
    sources = sorted(SOURCE_DIR.glob("*.c"))
    objects = [output.parent / f"{source.stem}.o" for source in sources]
    try:
        with ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as pool:
            compiles = [
                pool.submit(_run, [*compile_command, "-c", str(source), "-o", str(obj)], output.parent)
                for source, obj in zip(sources, objects)
            ]
            for future in compiles:
                future.result()
        _run([*link_command, *map(str, objects), "-pthread", "-o", str(output)], output.parent)
    except FileNotFoundError as error:
        raise RuntimeError(f"no C compiler to build the segmentation kernels: {error}") from error
    finally:
        for obj in objects:
            obj.unlink(missing_ok=True)
    return output
