"""The MAORIS kernels in C: the module holds every kernel, refuses wrong arguments, builds or says why."""

from __future__ import annotations

import importlib.machinery
import shlex

import numpy as np
import pytest


def test_the_c_module_holds_every_kernel(c_module):
    from ursim_core.segmentation.maoris.compiled import ENTRY_KERNELS

    wanted = {kernel for names in ENTRY_KERNELS.values() for kernel in names}
    assert wanted <= set(dir(c_module))


def _value_of(numba_type):
    """A small argument of ``numba_type`` (arrays are empty-ish: no kernel may run on them)."""
    from numba import types

    if isinstance(numba_type, types.BaseTuple):
        return tuple(_value_of(item) for item in numba_type.types)
    if isinstance(numba_type, types.Array):
        return np.zeros(
            (2,) * numba_type.ndim, dtype=numba_type.dtype.name if numba_type.dtype.name != "bool" else bool
        )
    if isinstance(numba_type, types.Float):
        return 0.5
    return 1


def _arrays_in(value, path=()):
    """Paths (indices into nested tuples) of the arrays of an argument list."""
    if isinstance(value, np.ndarray):
        yield path
    elif isinstance(value, tuple | list):
        for index, item in enumerate(value):
            yield from _arrays_in(item, (*path, index))


def _replaced(value, path, new):
    if not path:
        return new
    items = list(value)
    items[path[0]] = _replaced(items[path[0]], path[1:], new)
    return tuple(items) if isinstance(value, tuple) else items


def _get(value, path):
    for index in path:
        value = value[index]
    return value


def test_every_c_kernel_refuses_arrays_of_another_type_layout_or_writeability(c_module):
    """Each wrong argument is a TypeError before any work (numba's typed signatures refused
    them too); a C kernel trusting it would read out of bounds."""
    from ursim_core.segmentation.maoris.kernels import signatures

    checked = 0
    for (_, name), numba_types in signatures.SIGNATURES.items():
        kernel = getattr(c_module, name)
        good = [_value_of(numba_type) for numba_type in numba_types]
        with pytest.raises(TypeError):
            kernel(*good[:-1])
        for path in _arrays_in(good):
            original = _get(good, path)
            wrong_dtype = original.astype(np.float64 if original.dtype != np.float64 else np.int32)
            readonly = original.copy()
            readonly.flags.writeable = False
            other_ndim = original.reshape(-1) if original.ndim > 1 else original.reshape(1, -1)
            wrongs = [wrong_dtype, readonly, other_ndim, "not an array"]
            # Arguments typed any-layout (the free-space masks, windows of the map) take strides.
            if original.ndim == 2 and getattr(numba_types[path[0]], "layout", "C") != "A":
                wrongs.append(np.zeros((2, 4), original.dtype)[:, ::2])
            for wrong in wrongs:
                with pytest.raises(TypeError):
                    kernel(*_replaced(good, path, wrong))
                checked += 1
    assert checked > 100


def test_a_failing_compiler_is_reported_with_its_messages(tmp_path, monkeypatch):
    from ursim_core.segmentation.maoris import compiled

    script = "echo 'csrc/fusion.c:1: error: broken on purpose' >&2; exit 3"
    monkeypatch.setenv("CC", f"sh -c {shlex.quote(script)} sh")
    with pytest.raises(RuntimeError, match="(?s)exit 3.*broken on purpose"):
        compiled.build_ahead(tmp_path)
    assert not (tmp_path / compiled.DIGEST_NAME).exists()
    assert not list(tmp_path.glob("*" + importlib.machinery.EXTENSION_SUFFIXES[0]))


def test_no_compiler_is_reported_as_such(tmp_path, monkeypatch):
    from ursim_core.segmentation.maoris import compiled

    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    with pytest.raises(RuntimeError, match="no C compiler"):
        compiled.build_ahead(tmp_path)
    with monkeypatch.context() as failing:
        failing.setattr(compiled, "build_directories", lambda: [tmp_path / "empty"])
        with pytest.warns(RuntimeWarning, match="no C compiler.*numba's JIT"):
            assert compiled.build_or_warn() is None


def test_a_built_module_missing_a_kernel_is_not_used(tmp_path, monkeypatch, c_module):
    """A module built from other sources (or cut short) counts as broken: built again or the JIT."""
    from ursim_core.segmentation.maoris import compiled

    monkeypatch.setattr(compiled, "ENTRY_KERNELS", {**compiled.ENTRY_KERNELS, "extra": ("no_such_kernel",)})
    with pytest.raises(AttributeError, match="no_such_kernel"):
        compiled._load_ahead(compiled.ahead_module_path())


def _same(a, b) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    if isinstance(a, tuple):
        return isinstance(b, tuple) and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if a is None or b is None:
        return a is b
    return int(a) == int(b)


def _used_part(name, value):
    """What of a kernel's result numba defines: count_contacts and join_counts leave the
    candidate array past ``used`` uninitialised (np.empty), group_candidates its one slot when
    there is no candidate."""
    if name in ("count_contacts", "join_counts") and isinstance(value, tuple):
        return (value[0][: value[1]], *value[1:])
    if name == "group_candidates" and value[0].size == 1:
        return value[2:]
    return value


def test_every_c_kernel_gives_numba_results_and_leaves_its_arguments_alike(c_module, monkeypatch):
    """Each C kernel, called on copies of what numba's got during segmentations (every preset,
    contacts counted in bands, the watershed), returns the same and changes its arguments alike.

    adjacency's node arrays are allocated zeroed where numba's are np.empty (rows never read),
    so build_adjacency and _link_entries are compared on the labels they lead to (the end of
    the test) rather than on their raw arrays."""
    import copy

    from ursim_core.segmentation.maoris import (
        PRESETS,
        ZoneGraph,
        compiled,
        contact_tracking,
        flat_zones,
        inscribed_circle_image,
        maoris_labels,
        merge_ripples,
        quantize,
        remove_small_zones,
    )
    from ursim_core.segmentation.watershed import watershed_labels
    from ursim_core.synth import make_large_building

    monkeypatch.setenv("URSIM_KERNELS", "jit")
    compiled.forget()
    namespace = compiled.kernels()
    calls: dict[str, int] = {}
    differing: list[str] = []
    raw_arrays = {"build_adjacency", "_link_entries"}

    def checked(name, numba_kernel, c_kernel):
        def run(*args):
            c_args = copy.deepcopy(args)
            wanted, got = numba_kernel(*args), c_kernel(*c_args)
            if name not in raw_arrays and not _same(_used_part(name, wanted), _used_part(name, got)):
                differing.append(f"{name}: result")
            join = name == "join_counts"
            if not _same(
                tuple(_used_part(name, a) if join else a for a in args),
                tuple(_used_part(name, a) if join else a for a in c_args),
            ):
                differing.append(f"{name}: arguments")
            calls[name] = calls.get(name, 0) + 1
            return wanted

        return run

    try:
        for names in compiled.ENTRY_KERNELS.values():
            for name in names:
                monkeypatch.setattr(namespace, name, checked(name, getattr(namespace, name), getattr(c_module, name)))
        maps = [make_large_building(size, seed=seed).free for size, seed in ((300, 1), (500, 4))]
        for free in maps:
            for preset in ("default", "sketch", "robot"):
                maoris_labels(free, PRESETS[preset])
            watershed_labels(free, min_size=0, door_ratio=1.0)
            # The step on its own keeps the zone ids (expand_graph); maoris_labels renumbers.
            values = quantize(inscribed_circle_image(free))
            merge_ripples(remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=10))
        monkeypatch.setattr(contact_tracking, "_BAND_PIXELS", 0)
        monkeypatch.setattr(contact_tracking, "usable_cpus", lambda: 3)
        labels = maoris_labels(maps[1], PRESETS["robot"])
        padded = np.pad(labels.astype(np.int32), 2)
        alive = np.zeros(int(padded.max()) + 1, bool)
        alive[np.unique(padded)[1:]] = True
        namespace.contact_table(padded.ravel(), padded.shape[1], alive)
    finally:
        compiled.forget()
    assert not differing, differing[:10]
    every = {name for names in compiled.ENTRY_KERNELS.values() for name in names}
    assert set(calls) == every, every - set(calls)
    assert calls["join_counts"] >= 2


def _brick_zones(rows: int, cols: int) -> np.ndarray:
    """Zones laid as bricks (2 px wide, each row shifted by one): six neighbours each, more
    than the 4.5 node records per zone build_adjacency first makes room for."""
    row, col = np.indices((rows, cols))
    brick = (col + row % 2) // 2
    return (1 + (brick % 3) + 3 * (row % 2)).astype(np.uint8)


@pytest.mark.parametrize("shape", [(1, 1), (1, 7), (40, 60), (333, 201)])
def test_build_adjacency_grows_its_nodes_and_links_numbas_edges(c_module, shape):
    """The C kernel scans once and grows its node records (numba's scans twice, sizing them
    first): the records and every node it uses are numba's, and no unused node is returned."""
    from ursim_core.segmentation.maoris.kernels import adjacency
    from ursim_core.segmentation.maoris.zone_graph import flat_zones

    values = _brick_zones(*shape)
    zones = flat_zones(values)
    value, _ = c_module.zone_values_and_sizes(zones, values, int(zones.max()) + 1)
    records, nodes = c_module.build_adjacency(zones, value)
    want_records, want_nodes = adjacency.build_adjacency(zones, value)
    used = int(records[:, 2].sum())
    assert np.array_equal(records, want_records)
    assert len(nodes) == max(used, 2)
    assert np.array_equal(nodes[:used], want_nodes[:used])
    if shape[0] > 2:
        assert used > 5 * (len(value) - 1), "the bricks must need more room than the first guess"


def test_discs_painted_in_bands_are_numbas(c_module):
    """Images of 2**21 px and more are painted in bands of rows, one thread each: the radii
    are numba's (painted whole) to the pixel, obstacles included."""
    import cv2

    from ursim_core.segmentation.maoris.kernels import discs
    from ursim_core.synth import make_large_building

    free = make_large_building(1500, seed=5).free
    rng = np.random.default_rng(3)
    free[rng.random(free.shape) < 0.002] = False  # specks: many small discs near band edges
    assert free.size >= 1 << 21
    dist = np.empty(free.shape, np.float32)
    cv2.distanceTransform(free.view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE, dst=dist)
    shapes = c_module.centre_rectangles(dist, 500)
    # A strided mask: the kernel takes any layout, and numba's is compiled for that one only.
    mask = np.zeros((free.shape[0], 2 * free.shape[1]), np.uint8)[:, ::2]
    mask[...] = free
    got, want = np.zeros(free.shape, np.int32), np.zeros(free.shape, np.int32)
    c_module.paint_discs(shapes, mask, got)
    discs.paint_discs(shapes, mask, want)
    assert np.array_equal(got, want)
    assert (got[~free] == 0).all() and got.max() > 20


def _bands_run_here():
    import os

    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("one usable CPU: the kernels scan images whole, in no bands")


def _band_crossing_values() -> np.ndarray:
    """4 Mpx of zones that cross the band boundaries: on the left, rows joined at alternate ends
    (one zone snaking down the whole image); on the right, flat blocks of three values and specks."""
    rng = np.random.default_rng(7)
    values = np.zeros((2048, 2048), np.uint8)
    values[::2, :1024] = 5
    values[1::4, 1023] = 5
    values[3::4, 0] = 5
    blocks = rng.integers(0, 4, (2048 // 8, 1024 // 8)).astype(np.uint8)
    values[:, 1024:] = np.repeat(np.repeat(blocks, 8, 0), 8, 1)
    right = values[:, 1024:]
    right[rng.random(right.shape) < 0.002] = 9
    return values


def test_flat_zones_labelled_in_bands_are_numbas(c_module):
    """Images of 2**21 px and more are labelled in bands of rows, one thread each, and the
    bands joined: the labels (numbered in raster order of their first pixel), values and sizes
    are those numba's one pass gives, also for a zone that crosses every band."""
    from ursim_core.segmentation.maoris.kernels import flat_zones

    _bands_run_here()
    values = _band_crossing_values()
    identity = np.arange(256, dtype=np.uint8)  # radii that are their own values
    got, value, size = c_module.label_radii_zones_counted(values.astype(np.int32), 0, identity)
    want = flat_zones.label_flat_zones(values, np.empty(values.shape, np.int32))
    want_value, want_size = flat_zones.zone_values_and_sizes(want, values, int(want.max()) + 1)
    assert np.array_equal(got, want)
    assert np.array_equal(value, want_value) and np.array_equal(size, want_size)
    assert np.array_equal(c_module.label_flat_zones(values, np.empty(values.shape, np.int32)), want)
    snake = got[0, 0]
    assert snake == got[-2, 0] and size[snake] > 2048 * 1024 // 2  # one zone through every band


@pytest.mark.parametrize("threads", ["1", "3", " 2 ", "0", "many"])
def test_the_labels_do_not_depend_on_ursim_threads(c_module, monkeypatch, threads):
    """``URSIM_THREADS`` caps the C kernels' threads as ``ursim_core.cpus.usable_cpus`` does (1: the
    image whole; 3: three bands, whatever the machine; not a positive integer: ignored); the
    labels are numba's whatever it says."""
    from ursim_core.segmentation.maoris.kernels import flat_zones

    values = _band_crossing_values()
    want = flat_zones.label_flat_zones(values, np.empty(values.shape, np.int32))
    monkeypatch.setenv("URSIM_THREADS", threads)
    assert np.array_equal(c_module.label_flat_zones(values, np.empty(values.shape, np.int32)), want)


def test_centre_rectangles_scanned_in_bands_are_numbas(c_module):
    """The disc centres of 2**21 px and more are scanned in bands of rows: the rectangles,
    those that go on across a band's first row joined again, are numba's, in numba's order."""
    import cv2

    from ursim_core.segmentation.maoris.kernels import discs
    from ursim_core.synth import make_large_building

    _bands_run_here()
    free = make_large_building(1500, seed=5).free
    free[:, 700:760] = True  # a wide corridor through every band: tall rectangles across them
    rng = np.random.default_rng(3)
    free[rng.random(free.shape) < 0.002] = False
    dist = np.empty(free.shape, np.float32)
    cv2.distanceTransform(free.view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE, dst=dist)
    got, want = c_module.centre_rectangles(dist, 500), discs.centre_rectangles(dist, 500)
    assert got.shape == want.shape and np.array_equal(got, want)
    middle = free.shape[0] // 2
    assert ((want[:, 0] < middle) & (want[:, 1] >= middle)).any(), "a rectangle must cross the band boundary"


def test_values_looked_up_in_parts_are_the_tables_and_out_of_table_ones_refused(c_module):
    """The radii of 2**21 px and more are mapped to the value image in parts, one thread each:
    every pixel is the table's entry for it; a value outside the table is an IndexError, in C as
    in numba, not a read past the table."""
    from ursim_core.segmentation.maoris.kernels import discs

    rng = np.random.default_rng(11)
    values = rng.integers(-3, 300, (1500, 1500)).astype(np.int32)
    table = rng.integers(0, 256, 303).astype(np.uint8)
    got = np.zeros(values.shape, np.uint8)
    c_module.lookup_bytes(values, -3, table, got)
    assert np.array_equal(got, table[values + 3])
    values[-1, -1] = 300  # one past the table, in the last part
    for kernel in (c_module.lookup_bytes, discs.lookup_bytes):
        with pytest.raises(IndexError, match="outside"):
            kernel(values, -3, table, got)


def test_first_pixels_found_in_parts_are_numbas(c_module):
    """The first pixel of each label, in an image of 2**21 px and more looked at in parts on
    threads, is numba's (one pass): also for labels only in a later part, and absent ones."""
    from ursim_core.segmentation.maoris.kernels import flat_zones

    _bands_run_here()
    rng = np.random.default_rng(5)
    labels = rng.integers(0, 5000, (2048, 1100)).astype(np.int32)
    labels[1500:, :] = rng.integers(5000, 6000, (548, 1100))  # only in the last part
    got, want = c_module.first_pixels(labels, 6100), flat_zones.first_pixels(labels, 6100)
    assert np.array_equal(got, want)
    assert (got[6000:] == -1).all() and got[5000] >= 1500 * 1100
    labels[-1, -1] = 6100
    with pytest.raises(IndexError, match="outside"):
        c_module.first_pixels(labels, 6100)


def test_zones_labelled_over_their_radii_in_bands_are_the_value_images(c_module):
    """MAORIS steps 2 and 3 at once: the values looked up from the radii row by row as the rows
    are labelled, in bands of rows whose meeting rows are read before any band writes over
    them. The labels, values and sizes are those of labelling the value image itself, in C as
    in numba; a radius outside the table is an IndexError in both."""
    from ursim_core.segmentation.maoris.kernels import flat_zones

    _bands_run_here()
    values = _band_crossing_values()
    # Radii whose table gives those values: 0 -> 0, v -> v, and 10 + v -> v too (two radii of
    # one value side by side must still be one zone).
    radii = values.astype(np.int32)
    radii[:, 1024::2] += 10 * (radii[:, 1024::2] > 0)
    table = np.array([*range(10), 0, *range(1, 10)], np.uint8)
    want = flat_zones.label_flat_zones_counted(values, np.empty(values.shape, np.int32))
    for kernel in (c_module.label_radii_zones_counted, flat_zones.label_radii_zones_counted):
        got = kernel(radii.copy(), 0, table)
        assert all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
    assert want[0][0, 0] == want[0][-2, 0]  # the zone through every band
    radii[-1, -1] = len(table)
    for kernel in (c_module.label_radii_zones_counted, flat_zones.label_radii_zones_counted):
        with pytest.raises(IndexError, match="outside"):
            kernel(radii.copy(), 0, table)
