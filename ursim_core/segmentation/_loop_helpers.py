"""The decorator of the small helpers called in the compiled loops (numba).

A helper that takes arrays and never allocates one is compiled without
reference counting (numba's NRT) and inlined by LLVM. Inlined with NRT
(numba's ``inline="always"``), or called, such a helper leaves an atomic
increment and decrement per array argument in the loop, and at 4000 x 4000 px
those cost more than half of the time of some steps.
"""

from __future__ import annotations

from numba import njit

loop_helper = njit(cache=True, _nrt=False, forceinline=True)
