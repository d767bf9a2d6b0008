"""MAORIS step 3: flat zones and the zone graph (``ZoneExtractor.cpp``, ``GraphZone``).

:func:`flat_zones` labels the 4-connected components of equal value; :class:`ZoneGraph` holds
them with their 4-adjacency, the edge attributes (:class:`ZoneEdge`) and the contact counts that
the later steps (:mod:`.steps`) read and change.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ursim_core.errors import SegmentationError
from ursim_core.segmentation.maoris.compiled import kernels
from ursim_core.segmentation.maoris.kernels.constants import NO_MINIMUM

__all__ = ["flat_zones", "ZoneGraph", "ZoneEdge"]


def flat_zones(values: np.ndarray, *, out: np.ndarray | None = None) -> np.ndarray:
    """4-connected components of equal non-zero value.

    Zones are numbered 1..N in the raster order of their first pixel; 0 stays 0.

    Parameters
    ----------
    values : ndarray, shape (rows, cols)
    out : ndarray of int32, shape (rows, cols), C-ordered, keyword-only
        Where to write the labels (its content is ignored), e.g. an image no longer needed:
        at 8000 px a fresh 256 MB image costs more in page faults than labelling it.
        Default: a new array.

    Examples
    --------
    >>> flat_zones(np.array([[5, 5, 0], [0, 5, 7], [5, 0, 7]])).tolist()
    [[1, 1, 0], [0, 1, 2], [3, 0, 2]]
    """
    values, out = _value_bytes_and_out(values, out)
    return kernels().label_flat_zones(values, out)


def _value_bytes_and_out(values, out: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    values = np.asarray(values)
    if values.ndim != 2:
        raise SegmentationError(f"value image must be 2-D, got shape {values.shape}")
    if out is None:
        out = np.empty(values.shape, np.int32)
    elif out.shape != values.shape or out.dtype != np.int32 or not out.flags.c_contiguous:
        raise SegmentationError(f"out must be C-ordered int32 of shape {values.shape}")
    return _as_value_bytes(values), out


def _as_value_bytes(values: np.ndarray) -> np.ndarray:
    """The value image as C-ordered uint8 (the kernel's one signature), zones unchanged: other
    dtypes are ranked (0 stays 0), which keeps equal values equal and distinct ones distinct."""
    if values.dtype == np.uint8:
        return np.ascontiguousarray(values)
    distinct, rank = np.unique(values, return_inverse=True)
    nonzero = distinct != 0
    if int(nonzero.sum()) > 255:
        raise SegmentationError(
            f"value image has {int(nonzero.sum())} distinct non-zero values; at most 255 are supported"
        )
    codes = np.zeros(len(distinct), np.uint8)
    codes[nonzero] = np.arange(1, int(nonzero.sum()) + 1)
    return codes[rank.reshape(values.shape)]


class ZoneEdge:
    """Edge attributes: the lowest value met along fused paths, and breakability."""

    __slots__ = ("minimum", "unbreakable")

    def __init__(self, minimum: int | None = None, unbreakable: bool = False):
        self.minimum = minimum
        self.unbreakable = unbreakable

    def __repr__(self) -> str:
        return f"ZoneEdge(minimum={self.minimum}, unbreakable={self.unbreakable})"


_MISSING = object()
_PAD = 2  # label image padding: pixels next to a zone gather their own 3x3 neighbourhood


class ZoneGraph:
    """Zones (flat zones, later regions) and their adjacency, as the C++ GraphZone.

    Vertices are zone ids kept in insertion order (ascending id = raster order
    of the first pixel); each vertex's neighbours are kept in edge-insertion
    order. A fusion moves the absorbed zone's pixels and transfers its edges.

    The adjacency has two forms. A new graph keeps it in compact arrays (see
    :mod:`.kernels`): a large map starts with millions of flat zones, and
    the first steps (:func:`remove_small_zones`, :func:`merge_ripples`) run
    on them as compiled code. The first access to :attr:`adj` turns it into
    dicts, which the later steps, on a few hundred zones, read and change;
    a compiled step converts them back.

    Contacts (contour pixels of a zone having another zone in their 3x3
    neighbourhood) are counted for the whole image by compiled code when first
    queried, and dropped by the next fusion; the compiled steps that need them
    while fusing track them incrementally themselves. Fusions in dict form
    are only recorded; the label image is rewritten once, when next needed.

    Parameters
    ----------
    zones : ndarray of int, shape (rows, cols)
        Zone labels 1..N (0 = no zone), e.g. from :func:`flat_zones`.
    values : ndarray, shape (rows, cols)
        The value of every pixel; each zone must be flat.

    Examples
    --------
    >>> values = np.array([[10, 10, 20], [10, 10, 20]], np.uint8)
    >>> graph = ZoneGraph(flat_zones(values), values)
    >>> graph.vertices(), graph.neighbours(1), graph.contact_percent(2, 1)
    ([1, 2], [2], 100)
    """

    def __init__(self, zones: np.ndarray, values: np.ndarray):
        zones = np.asarray(zones)
        values = np.asarray(values)
        if zones.shape != values.shape or zones.ndim != 2:
            raise SegmentationError(f"zones {zones.shape} and values {values.shape} must be 2-D of equal shape")
        zones = zones.astype(np.int32, copy=False)
        value, size = kernels().zone_values_and_sizes(zones, values, int(zones.max(initial=0)) + 1)
        self._set_up(zones, value, size, None)

    @classmethod
    def _of_zone_values(cls, zones: np.ndarray, value: np.ndarray, size: np.ndarray, *, storage) -> ZoneGraph:
        """The graph of C-ordered int32 ``zones`` whose values and sizes the caller took
        (``zone_values_and_sizes``): the value image can go before the graph is built, the
        step of the peak memory (64 MB at 8000 px, touched afresh otherwise). ``storage``: int32
        memory whose first pixels are ``zones``, with room for them padded (the labels are
        padded in it, in place, not copied), or None."""
        graph = cls.__new__(cls)
        graph._set_up(zones, value, size, storage)
        return graph

    def _set_up(self, zones: np.ndarray, value: np.ndarray, size: np.ndarray, storage: np.ndarray | None) -> None:
        self.shape = zones.shape
        self._size = size
        self._value_array = value
        # Values of the zones read one by one (the steps on dicts): filled as they are asked
        # for. A list of all of them was 52 MB of fresh memory at 8000 px, for a few hundred.
        self._values_read: dict[int, int] = {}
        # The adjacency lives either in compact arrays (the compiled steps'
        # form, cheap for millions of zones) or in `_adj` dicts (see `adj`).
        self._alive = self._size > 0
        self._alive[0] = False
        self._compact: tuple | None = kernels().build_adjacency(zones, value)
        self._labels = np.pad(zones, _PAD) if storage is None else _pad_in_place(zones, storage)
        self._storage = storage  # the memory the labels are padded in, if given
        self._adj: dict[int, dict[int, ZoneEdge | None]] | None = None
        # Contact counts, computed for the whole image when first queried and
        # dropped by the next fusion (the compiled steps track their own).
        self._contacts: dict[int, int] | None = None
        # Fusions not yet written into the label image: zone -> receiver (0 = deleted).
        self._pending: dict[int, int] = {}
        # The lookup of _flush, made at its first flush (one entry per zone).
        self._identity: np.ndarray | None = None

    @property
    def adj(self) -> dict[int, dict[int, ZoneEdge | None]]:
        """``adj[a][b]``: the edge between a and b, or None for a plain edge (no
        minimum, breakable) never touched; :meth:`edge` always gives a
        :class:`ZoneEdge`. Read-only for callers: mutate through :meth:`fuse`
        and :meth:`remove`."""
        if self._adj is None:
            self._adj = self._adjacency_dicts()
            self._compact = None
        return self._adj

    def _adjacency_dicts(self) -> dict[int, dict[int, ZoneEdge | None]]:
        adj: dict[int, dict[int, ZoneEdge | None]] = {zone: {} for zone in np.flatnonzero(self._alive).tolist()}
        edges: dict[int, ZoneEdge | None] = {}  # node -> the edge object both directions share
        for zone, other, node, twin, low, unbreakable in (
            kernels().adjacency_entries(self._alive, self._compact).tolist()
        ):
            edge = edges.pop(twin, _MISSING)
            if edge is _MISSING:
                edge = None if low < 0 and not unbreakable else ZoneEdge(None if low < 0 else low, bool(unbreakable))
                edges[node] = edge
            adj[zone][other] = edge
        return adj

    def _compact_adjacency(self) -> tuple:
        """The adjacency as compact arrays (converted from `_adj` if needed)."""
        if self._compact is None:
            entries = [
                (a, b, NO_MINIMUM if edge is None or edge.minimum is None else edge.minimum,
                 edge is not None and edge.unbreakable)
                for a, neighbours in self._adj.items()
                for b, edge in neighbours.items()
            ]  # fmt: skip
            columns = list(zip(*entries)) or [()] * 4
            zone, other, minimum = (np.array(column, np.int32) for column in columns[:3])
            unbreakable = np.array(columns[3], bool)
            self._compact = _adjacency_from_entries(zone, other, minimum, unbreakable, self._value_array)
            self._alive = np.zeros(len(self._value_array), bool)
            self._alive[list(self._adj)] = True
            self._adj = None
        return self._compact

    def _run_compiled(self) -> tuple:
        """Prepare for a compiled step: labels flushed, contacts dropped."""
        self._flush()
        self._contacts = None
        return self._compact_adjacency()

    # -- queries ----------------------------------------------------------

    def vertices(self) -> list[int]:
        """Zone ids in insertion order."""
        if self._adj is None:
            return np.flatnonzero(self._alive).tolist()
        return list(self._adj)

    def __len__(self) -> int:
        return int(self._alive.sum()) if self._adj is None else len(self._adj)

    def __contains__(self, zone: object) -> bool:
        if self._adj is not None:
            return zone in self._adj
        return isinstance(zone, (int, np.integer)) and 0 < zone < len(self._alive) and bool(self._alive[zone])

    def neighbours(self, zone: int) -> list[int]:
        """Neighbours of ``zone`` in edge-insertion order."""
        return list(self.adj[zone])

    def edge(self, a: int, b: int) -> ZoneEdge:
        """Attributes of the edge between ``a`` and ``b`` (``adj[a][b]`` may hold None
        for a plain edge; this materialises it)."""
        edge = self.adj[a][b]
        if edge is None:
            edge = self.adj[a][b] = self.adj[b][a] = ZoneEdge()
        return edge

    def value(self, zone: int) -> int:
        """Quantised value of a zone (it keeps it when other zones are fused into it)."""
        known = self._values_read.get(zone)
        if known is None:
            known = self._values_read[zone] = int(self._value_array[zone])
        return known

    def size(self, zone: int) -> int:
        """Number of pixels of a zone."""
        return int(self._size[zone])

    @property
    def labels(self) -> np.ndarray:
        """Current zone label image, shape ``self.shape`` (a view, rewritten in place by later
        fusions; do not modify)."""
        self._flush()
        return self._labels[_PAD:-_PAD, _PAD:-_PAD]

    def contact_percent(self, zone: int, other: int) -> int:
        """Integer percentage of ``zone``'s contour pixels having ``other`` in their 3x3 neighbourhood."""
        return self.contact_percents(zone)(other)

    def contact_percents(self, zone: int) -> Callable[[int], int]:
        """A function ``other -> contact_percent(zone, other)`` valid until the next fusion.

        Faster than repeated :meth:`contact_percent` calls for one zone.
        """
        contacts = self._ensure_contacts()
        key = zone * len(self._value_array)
        total = contacts.get(key, 0)
        if total == 0:
            return lambda other: 0
        get = contacts.get
        return lambda other: get(key + other, 0) * 100 // total

    def contact_sum(self, zone: int) -> int:
        """Sum of :meth:`contact_percent` over the graph neighbours of ``zone``."""
        percents = self.contact_percents(zone)
        return sum(percents(other) for other in self.adj[zone])

    def label_image(self) -> np.ndarray:
        """Labels renumbered 1..N in the raster order of each region's first pixel."""
        return self._renumbering()[self.labels]

    def _renumbering(self) -> np.ndarray:
        """The lookup zone -> label of :meth:`label_image` (flushes)."""
        self._flush()
        zones = np.array(self.vertices(), np.int64)
        # The padding adds no labels, so raster order in it is raster order in the map.
        first = kernels().first_pixels(self._labels, len(self._value_array))[zones]
        lookup = np.zeros(len(self._value_array), np.int32)
        lookup[zones[np.argsort(first, kind="stable")]] = np.arange(1, len(zones) + 1, dtype=np.int32)
        return lookup

    def _write_label_image(self, out: np.ndarray) -> None:
        """Write :meth:`label_image` into ``out`` (shape ``self.shape``, any strides), renumbering
        the graph's own labels in place: the graph must not be used afterwards. At 8000 px this
        spares a fresh 256 MB image (its page faults cost more than the pass)."""
        kernels().relabel(self._labels.ravel(), self._renumbering())
        out[...] = self._labels[_PAD:-_PAD, _PAD:-_PAD]

    def _label_image_in_storage(self, shape: tuple[int, int], origin: tuple[int, int]) -> np.ndarray | None:
        """:meth:`label_image` placed at ``origin`` (row, col) of an image of ``shape``, zeros
        elsewhere, made in the graph's own memory, or None when that memory cannot hold
        ``shape`` (then use :meth:`_write_label_image`). The graph must not be used afterwards.
        No image is allocated: at 8000 px a fresh one, 256 MB, cost 0.4-0.5 s of page faults."""
        storage = self._storage
        if storage is None or storage.size < shape[0] * shape[1]:
            return None
        kernels().relabel(self._labels.ravel(), self._renumbering())
        return _place_in_place(self._labels, storage, shape, origin)

    def _renumbered(self, original: np.ndarray, size: np.ndarray, alive: np.ndarray, compact: tuple) -> None:
        """Become the graph of zones renumbered 1..n (zone k was ``original[k - 1]``, in
        increasing order), with the labels already so renumbered, their sizes ``size``,
        ``alive`` and adjacency ``compact`` indexed by the new ids (see :func:`.steps.merge_ripples`)."""
        if self._pending or self._adj is not None:
            raise SegmentationError("only a compact graph with no pending fusion can be renumbered")
        value = np.zeros(len(original) + 1, np.int32)
        value[1:] = self._value_array[original]
        self._value_array, self._values_read = value, {}
        self._size, self._alive, self._compact = size, alive, compact
        self._contacts, self._identity = None, None

    # -- contacts and relabelling -------------------------------------------

    def _flush(self) -> None:
        """Write the pending fusions into the label image, in one vectorised pass."""
        if not self._pending:
            return
        pending = self._pending
        zones = np.fromiter(pending.keys(), np.int64, len(pending))
        # A persistent identity lookup, patched for this flush: allocating one per
        # flush would cost O(zones) each time.
        if self._identity is None:
            self._identity = np.arange(len(self._value_array), dtype=np.int32)
        parent = self._identity
        parent[zones] = np.fromiter(pending.values(), np.int64, len(pending))
        # Follow chains z -> b -> c so every pending zone maps to its final
        # receiver: pointer doubling, log(chain length) vectorised passes.
        while True:
            jumped = parent[parent[zones]]
            if np.array_equal(jumped, parent[zones]):
                break
            parent[zones] = jumped
        # In place: parent[self._labels] allocated a fresh full-size image (256 MB at 8000 px),
        # whose page faults cost more than the pass. Views taken earlier (``labels``) change too.
        kernels().relabel(self._labels.ravel(), parent)
        parent[zones] = zones
        self._pending = {}

    def _ensure_contacts(self) -> dict[int, int]:
        # Counts keyed by ``a * base + b``: contour pixels of a with b in their
        # 3x3 neighbourhood (b >= 1), and the contour size of a (b = 0).
        if self._contacts is None:
            self._flush()
            alive = np.zeros(len(self._value_array), bool)
            alive[self.vertices()] = True
            table = kernels().contact_table(self._labels.ravel(), self._labels.shape[1], alive)
            codes = table[:, 0] * len(self._value_array) + table[:, 1]
            self._contacts = dict(zip(codes.tolist(), table[:, 2].tolist()))
        return self._contacts

    # -- mutations -------------------------------------------------------

    def fuse(self, zone: int, into: int) -> None:
        """Fuse ``zone`` into its neighbour ``into``: pixels, size and edges move.

        ``into`` keeps its value. An edge (zone, n) whose n is not yet a
        neighbour of ``into`` becomes a new edge (into, n) recording the lowest
        value met, ``min(value(zone), minimum of (zone, n))``; an existing
        (into, n) keeps its minimum. Unbreakable edges stay unbreakable. No
        self-loops or duplicate edges.

        Examples
        --------
        >>> values = np.array([[90, 40, 90]], np.uint8)
        >>> graph = ZoneGraph(flat_zones(values), values)
        >>> graph.fuse(2, 1)
        >>> graph.neighbours(1), graph.edge(1, 3).minimum, graph.size(1)
        ([3], 40, 2)
        """
        if zone == into:
            raise SegmentationError(f"cannot fuse zone {zone} into itself")
        self._pending[zone] = into
        self._contacts = None
        self._size[into] += self._size[zone]
        zone_value = self.value(zone)
        adj = self.adj
        target = adj[into]
        for neighbour, old in adj.pop(zone).items():
            neighbour_adj = adj[neighbour]
            del neighbour_adj[zone]
            if neighbour == into:
                continue
            if neighbour not in target:
                if old is None or old.minimum is None or zone_value < old.minimum:
                    minimum = zone_value
                else:
                    minimum = old.minimum
                edge = ZoneEdge(minimum, old is not None and old.unbreakable)
                target[neighbour] = edge
                neighbour_adj[into] = edge
            elif old is not None and old.unbreakable:
                # A direct contact already exists: no valley between the two,
                # keep its minimum; unbreakability is kept.
                self.edge(into, neighbour).unbreakable = True

    def remove(self, zone: int) -> None:
        """Delete a zone: its pixels become 0 and its edges disappear."""
        self._pending[zone] = 0
        self._contacts = None
        for neighbour in self.adj.pop(zone):
            del self.adj[neighbour][zone]


def _pad_in_place(zones: np.ndarray, storage: np.ndarray) -> np.ndarray:
    """``np.pad(zones, _PAD)`` written in ``storage``, whose first pixels ``zones`` are."""
    rows, cols = zones.shape
    padded = storage[: (rows + 2 * _PAD) * (cols + 2 * _PAD)].reshape(rows + 2 * _PAD, cols + 2 * _PAD)
    if zones.ctypes.data != storage.ctypes.data or not zones.flags.c_contiguous:
        raise SegmentationError("zones must be the first pixels of their storage")
    # Last row first: each row moves to a later place than any row above it starts from.
    for row in range(rows - 1, -1, -1):
        padded[row + _PAD, _PAD : _PAD + cols] = zones[row]
    padded[:_PAD] = padded[-_PAD:] = 0
    padded[:, :_PAD] = padded[:, -_PAD:] = 0
    return padded


def _place_in_place(padded: np.ndarray, storage: np.ndarray, shape: tuple[int, int], origin: tuple[int, int]):
    """``padded[_PAD:-_PAD, _PAD:-_PAD]`` placed at ``origin`` of a C-ordered image of ``shape``
    (zeros elsewhere) made in the first pixels of ``storage``, the memory ``padded`` starts.

    Row i moves from P(i) to D(i), both increasing with i, and rows are shorter than the
    distance between two P or two D. The rows that move back (D < P) go first, in increasing
    order: each lands before its own source, so before every source still to read. The rows
    that move on then go in decreasing order: each lands after its own source, so after every
    source still to read. The zeros go last, around the placed rows."""
    rows, cols = padded.shape[0] - 2 * _PAD, padded.shape[1] - 2 * _PAD
    height, width = shape
    top, left = origin
    if padded.ctypes.data != storage.ctypes.data or not padded.flags.c_contiguous:
        raise SegmentationError("the padded labels must be the first pixels of their storage")
    if top < 0 or left < 0 or top + rows > height or left + cols > width:
        raise SegmentationError(f"labels of {rows}x{cols} do not fit at {origin} in {shape}")
    source = [(row + _PAD) * (cols + 2 * _PAD) + _PAD for row in range(rows)]
    target = [(top + row) * width + left for row in range(rows)]
    back = [row for row in range(rows) if target[row] < source[row]]
    on = [row for row in range(rows) if target[row] >= source[row]]
    for row in back + on[::-1]:
        # numpy copies through a buffer when a row overlaps its own place
        storage[target[row] : target[row] + cols] = storage[source[row] : source[row] + cols]
    ends = [0] + [start + cols for start in target]
    starts = target + [height * width]
    for end, start in zip(ends, starts):
        storage[end:start] = 0
    return storage[: height * width].reshape(height, width)


def _adjacency_from_entries(zone, other, minimum, unbreakable, value):
    """Zone graph from (zone, neighbour, minimum, unbreakable) entries, each
    zone's in list order: the inverse of the kernel ``adjacency_entries``. Every edge
    must appear in both directions, with the same attributes."""
    # Entry i of an edge (low -> high) owns the node pair 2i, 2i + 1; the
    # reversed entry finds it by key. The keys are distinct, so any sort gives the
    # same owners; numpy's sort here spares compiling numba's (about 5 s).
    count = len(value)
    keys = zone.astype(np.int64) * count + other
    order = np.argsort(keys)
    low, high = np.minimum(zone, other).astype(np.int64), np.maximum(zone, other)
    owner = order[np.searchsorted(keys[order], low * count + high)]
    return kernels()._link_entries(zone, other, owner, minimum, unbreakable, value)
