"""Where the MAORIS kernels' C sources live, and how they are compiled into ``_maoris_kernels``.

The sources of :file:`csrc` are compiled by :class:`ursim_core.native.NativeModule` (for this
module, :func:`ursim_core.segmentation.maoris.compiled.build_ahead`): each source file by a
process of its own (the C compiler Python was built with, ``sysconfig``'s ``CC``), as many at once
as there are CPUs, then linked (``LDSHARED``), with NumPy's headers. This replaced numba's
``pycc`` build of the same kernels (deprecated by numba, and 16.6 s on two CPUs for what the C
compiler does in a few seconds). The planar matcher's module is built the same way.

Floating point is compiled as written (``-ffp-contract=off``: no fused multiply-adds, no
``-ffast-math``, :data:`CFLAGS`), so that the kernels compute what numba's do, bit for bit. This
file is part of the built module's digest: a change here builds the kernels again.
"""

from __future__ import annotations

from pathlib import Path

from ursim_core.native import CFLAGS

__all__ = ["SOURCE_DIR", "CFLAGS"]

SOURCE_DIR = Path(__file__).resolve().parent / "csrc"
"""Where the C sources of the kernels live."""
