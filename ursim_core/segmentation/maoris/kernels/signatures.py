"""The one signature of every MAORIS kernel called from Python, and compiling them.

Each kernel is compiled for exactly these argument types (a test checks that a
segmentation calls nothing else), so compiling them ahead needs no example input, and
the kernels can be compiled in groups, one process per group, into numba's cache:
:func:`compile_group` is what each process runs (see
:func:`ursim_core.segmentation.maoris.pipeline.compile_kernels`).
"""

from __future__ import annotations

from numba import types

from ursim_core.segmentation.maoris.kernels import adjacency, contacts, discs, distance, flat_zones, flooding, fusion

__all__ = ["SIGNATURES", "RETURN_TYPES", "GROUPS", "compile_group", "takes_any_layout", "declared_only"]

_I32, _I64, _BOOL, _U8 = types.int32[::1], types.int64[::1], types.bool_[::1], types.uint8[::1]
_I32_2D, _I64_2D = types.int32[:, ::1], types.int64[:, ::1]
_F32_2D, _U8_2D, _U32_2D = types.float32[:, ::1], types.uint8[:, ::1], types.uint32[:, ::1]
_U8_2D_ANY = types.uint8[:, :]
_INT, _FLOAT = types.int64, types.float64
# The compact zone graph (records, nodes); the contact counts of count_contacts; the
# tracking state of start_tracking (original, compact_of, (parent, pixels, ...)).
_GRAPH = types.UniTuple(_I32_2D, 2)
_COUNTS = types.Tuple((_I32, _INT, _I64, _I64, _I64, _I64, _I64))
_STATE = types.Tuple((_I32, _I32, _I32, _I32, _I32, _I64, _I64, _I64, _I64, _I64))
_TRACKING = types.Tuple((_I32, _I32, _STATE))

#: ``(module, kernel name) -> argument types``.
SIGNATURES: dict[tuple[str, str], tuple] = {
    ("distance", "distance_transform"): (_U8_2D_ANY, _F32_2D),
    ("discs", "centre_rectangles"): (_F32_2D, _INT),
    ("discs", "paint_discs"): (_I64_2D, _U8_2D_ANY, _I32_2D),
    ("discs", "lookup_bytes"): (_I32_2D, _INT, _U8, _U8_2D),
    ("flat_zones", "label_flat_zones"): (_U8_2D, _I32_2D),
    ("flat_zones", "label_radii_zones_counted"): (_I32_2D, _INT, _U8),
    ("flat_zones", "zone_values_and_sizes"): (_I32_2D, _U8_2D, _INT),
    ("flat_zones", "first_pixels"): (_I32_2D, _INT),
    ("flat_zones", "resolve_parents"): (_I32, _BOOL),
    ("flat_zones", "relabel"): (_I32, _I32),
    ("adjacency", "build_adjacency"): (_I32_2D, _I32),
    ("adjacency", "adjacency_entries"): (_BOOL, _GRAPH),
    ("adjacency", "_link_entries"): (_I32, _I32, _I64, _I32, _BOOL, _I32),
    ("adjacency", "remove_small_zones"): (_INT, _I64, _BOOL, _I32, _GRAPH),
    ("adjacency", "compact_graph"): (_I32, _I32, _GRAPH),
    ("adjacency", "expand_graph"): (_I32, _GRAPH, _I32_2D),
    ("contacts", "_compact_labels"): (_I32, _BOOL),
    ("contacts", "count_contacts"): (_I32, _INT, _INT, _INT, _INT),
    ("contacts", "join_counts"): (_COUNTS, _COUNTS),
    ("contacts", "group_candidates"): (_I32, _I32, _INT, _INT),
    ("contacts", "contact_table"): (_I32, _INT, _BOOL),
    ("fusion", "merge_ripples"): (_I32, _FLOAT, _I32, _INT, _I64, _BOOL, _GRAPH, _TRACKING),
    ("fusion", "remove_doors"): (_FLOAT, _I32, _INT, _I64, _BOOL, _GRAPH, _TRACKING),
    ("flooding", "flood_levels"): (_U32_2D, _I32_2D, _U8_2D, _INT),
    ("flooding", "clearance_levels"): (_F32_2D, _U8_2D),
}

#: ``(module, kernel name) -> return type``, as numba's typing gives it for
#: :data:`SIGNATURES` (a test checks): the ahead-of-time build needs them, and typing every
#: kernel to learn them cost seconds of that build.
RETURN_TYPES: dict[tuple[str, str], types.Type] = {
    ("distance", "distance_transform"): types.none,
    ("discs", "centre_rectangles"): _I64_2D,
    ("discs", "paint_discs"): types.none,
    ("discs", "lookup_bytes"): types.none,
    ("flat_zones", "label_flat_zones"): _I32_2D,
    ("flat_zones", "label_radii_zones_counted"): types.Tuple((_I32_2D, _I32, _I64)),
    ("flat_zones", "zone_values_and_sizes"): types.Tuple((_I32, _I64)),
    ("flat_zones", "first_pixels"): _I64,
    ("flat_zones", "resolve_parents"): types.none,
    ("flat_zones", "relabel"): types.none,
    ("adjacency", "build_adjacency"): _GRAPH,
    ("adjacency", "adjacency_entries"): _I64_2D,
    ("adjacency", "_link_entries"): _GRAPH,
    ("adjacency", "remove_small_zones"): types.none,
    ("adjacency", "compact_graph"): _GRAPH,
    ("adjacency", "expand_graph"): types.none,
    ("contacts", "_compact_labels"): types.Tuple((_I32, _I32, _INT)),
    ("contacts", "count_contacts"): _COUNTS,
    ("contacts", "join_counts"): _COUNTS,
    ("contacts", "group_candidates"): types.UniTuple(_I32, 4),
    ("contacts", "contact_table"): _I64_2D,
    ("fusion", "merge_ripples"): types.none,
    ("fusion", "remove_doors"): types.none,
    ("flooding", "flood_levels"): _INT,
    ("flooding", "clearance_levels"): _U32_2D,
}

_MODULES = {
    "distance": distance,
    "discs": discs,
    "flat_zones": flat_zones,
    "adjacency": adjacency,
    "contacts": contacts,
    "fusion": fusion,
    "flooding": flooding,
}

#: Kernel groups of about equal compilation time (measured), one process each.
GROUPS: tuple[tuple[tuple[str, str], ...], ...] = (
    tuple(key for key in SIGNATURES if key[0] in ("fusion", "contacts")),
    tuple(key for key in SIGNATURES if key[0] not in ("fusion", "contacts")),
)


def kernel(key: tuple[str, str]):
    """The numba dispatcher of ``(module, name)``."""
    return getattr(_MODULES[key[0]], key[1])


def compile_group(index: int | None = None) -> None:
    """Compile (or load from numba's cache) the kernels of ``GROUPS[index]``, or all."""
    keys = SIGNATURES if index is None else GROUPS[index]
    for key in keys:
        _compile(key)


def _compile(key: tuple[str, str]) -> None:
    """Compile (or load) the declared signature of ``key`` unless the dispatcher has it: numba
    would not compile it again, but refuses the call altogether once :func:`declared_only`
    turned its compilation off."""
    if tuple(SIGNATURES[key]) not in kernel(key).overloads:
        kernel(key).compile(SIGNATURES[key])


def takes_any_layout(key: tuple[str, str]) -> bool:
    """Whether kernel ``key`` declares an array argument of any layout (``uint8[:, :]``).

    numba types a C-contiguous array as ``[:, ::1]``, and a dispatcher that may still compile
    specialises for that exact type instead of converting it to the declared one: a free-space
    window that is the whole image (the map's free space touching its border) cost a second
    compilation of ``distance_transform`` and ``paint_discs`` (1.3 s the first time, 0.3 s a
    process to load it from the cache afterwards).
    """
    return any(isinstance(argument, types.Array) and argument.layout == "A" for argument in SIGNATURES[key])


def declared_only(key: tuple[str, str]):
    """The dispatcher of ``key``, compiled (or loaded from numba's cache) for its declared
    signature, with further specialisation turned off: numba then converts the arguments of
    every call to that signature (a C-contiguous array to one of any layout) or raises
    TypeError, and never compiles another version."""
    _compile(key)
    dispatcher = kernel(key)
    dispatcher.disable_compile()
    return dispatcher
