"""Small compiled helpers shared by the MAORIS kernels (numba).

A helper that takes arrays and never allocates one is compiled without
reference counting (numba's NRT) and inlined by LLVM (:data:`loop_helper`).
Inlined with NRT (numba's ``inline="always"``), or called, such a helper
leaves an atomic increment and decrement per array argument in the loop, and
at 4000 x 4000 px those cost more than half of the time of some steps.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

# Neither decorator caches nor builds the wrappers that let Python call a function
# (``no_cpython_wrapper``): a helper is compiled into the kernels that call it, and
# those are cached whole. Each cached or wrapped function costs a few tenths of a
# second when the kernels compile on an empty cache, and there are about fifty.
loop_helper = njit(_nrt=False, forceinline=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)
"""Decorator of the helpers called in the compiled loops: no NRT, always inlined."""

inner_kernel = njit(no_cpython_wrapper=True, no_cfunc_wrapper=True)
"""Decorator of the compiled functions that only other compiled functions call."""


@intrinsic
def _prefetch(typingctx, array, index):
    """Ask the CPU to start loading the cache line of ``array[index]`` (no
    bounds check; a hint only, never faults). A fusion's border pixels lie on
    distinct rows of a label image far larger than the cache: loading a few
    pixels ahead overlaps their memory latencies."""
    signature = types.void(array, index)

    def codegen(context, builder, signature, args):
        array_type = signature.args[0]
        array_value = context.make_array(array_type)(context, builder, args[0])
        pointer = cgutils.get_item_pointer(context, builder, array_type, array_value, [args[1]], wraparound=False)
        i32 = ir.IntType(32)
        prefetch = cgutils.get_or_insert_function(
            builder.module, ir.FunctionType(ir.VoidType(), [pointer.type, i32, i32, i32]), "llvm.prefetch.p0"
        )
        builder.call(prefetch, [pointer, i32(0), i32(3), i32(1)])  # read, keep in all levels, data
        return context.get_dummy_value()

    return signature, codegen


@inner_kernel
def _filled(size, fill, dtype):
    # np.full and slice assignments cost seconds of compilation each; loops do not.
    array = np.empty(size, dtype)
    for i in range(size):
        array[i] = fill
    return array


@inner_kernel
def _grown(array, capacity, fill):
    grown = np.empty(capacity, array.dtype)
    for i in range(capacity):
        grown[i] = array[i] if i < len(array) else fill
    return grown


@loop_helper
def _zone_of(label, parent):
    """Current zone of an original label (union-find root, with path halving)."""
    while parent[label] != label:
        parent[label] = parent[parent[label]]
        label = parent[label]
    return label


@loop_helper
def _bits(size):
    """log2 of a power of two."""
    bits = 0
    while (1 << bits) < size:
        bits += 1
    return bits
