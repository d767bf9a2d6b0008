"""Compiling the MAORIS kernels in C (:file:`csrc`) into the extension module ``_maoris_kernels``.

Each source file is compiled by a process of its own (the C compiler Python was built with,
``sysconfig``'s ``CC``), as many at once as there are CPUs, then linked (``LDSHARED``):
:func:`ursim_core.native.compile_extension`, which the planar matcher's kernel shares.
This replaced numba's ``pycc`` build of the same kernels (deprecated by numba, and 16.6 s on
two CPUs for what the C compiler does in a few seconds).

Floating point is compiled as written (``-ffp-contract=off``: no fused multiply-adds, no
``-ffast-math``), so that the kernels compute what numba's do, bit for bit.
"""

from __future__ import annotations

from pathlib import Path

from ursim_core.native import CFLAGS, compile_extension

__all__ = ["SOURCE_DIR", "CFLAGS", "build_module", "source_files"]

SOURCE_DIR = Path(__file__).resolve().parent / "csrc"
"""Where the C sources of the kernels live."""


def source_files() -> list[Path]:
    """The sources and headers the module is built from, in a stable order (for the digest)."""
    return sorted([*SOURCE_DIR.glob("*.c"), *SOURCE_DIR.glob("*.h")])


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
    try:
        return compile_extension(
            sorted(SOURCE_DIR.glob("*.c")), output, include_dirs=[SOURCE_DIR], numpy=True, jobs=jobs
        )
    except RuntimeError as error:
        if str(error).startswith("no C compiler"):
            raise RuntimeError(f"no C compiler to build the segmentation kernels: {error}") from error
        raise
