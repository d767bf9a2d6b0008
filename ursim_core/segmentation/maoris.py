"""MAORIS room segmentation: a faithful and fast port of the authors' C++.

MAORIS (Mielle, Magnusson, Lilienthal, ICRA 2018) segments a free-space mask
into rooms in seven steps, each a public function here so that it can be
tested on its own:

1. :func:`inscribed_circle_radii` / :func:`inscribed_circle_image`: every free
   pixel gets the radius of the largest inscribed disc containing it
   (``FuzzyOpening.cpp``), min-max normalised to 0..255.
2. :func:`quantize`: normalise again and round up to multiples of 5
   (``ZoneReducer.hpp``).
3. :func:`flat_zones`: 4-connected components of equal non-zero value, and
   :class:`ZoneGraph`, their 4-adjacency graph (``ZoneExtractor.cpp``).
4. :func:`remove_small_zones` (< 10 px), :func:`merge_ripples`,
   :func:`mark_unbreakable_edges` (``GraphZone::removeRiplesv3``).
5. :func:`watershed_merge` (``GraphZone::watershed``).
6. :func:`remove_doors` (``GraphZone::removeDoors``).
7. :func:`remove_small_zones` (< 100 px) and :func:`remove_isolated_zones`.

:func:`maoris_labels` runs them all.

Speed: a 4000 x 4000 map starts with about 1.5 million flat zones, visited
one by one in an order that decides ties, so the graph steps cannot be
vectorised; steps 3, 4 and 6 run as compiled code (numba, ``_zone_kernels``)
on an array form of the zone graph, and step 1 paints its discs with compiled
code too (``_disc_kernels``). The contacts of large maps are counted in bands
of rows on one thread per CPU. The kernels compile on first use, about 43 s,
once: numba caches them beside the module (or in ``NUMBA_CACHE_DIR``).

Faithfulness notes (see ../shared/design/original_code.md, section 2):

* The C++ paints, for every free pixel q with r = min(int(dist(q)), 500), a
  disc of radius r - 1 centred at q - (1, 1). This port **reproduces the
  one-pixel shift**: the authors' own label images
  (``maoris_segmentation/sketches/maoris_output``) leave exactly the free
  pixels just above or left of a wall unlabelled, which only the shift
  explains. ``cv::circle`` filled discs are exactly the lattice discs
  ``{o : |o|^2 <= i^2}`` (checked for every radius up to 500), so painting
  those lattice discs (row spans with integer half-widths ``isqrt(i^2 - dy^2)``)
  gives the C++ image bit for bit.
* Contour pixels of a zone (``findContours(RETR_LIST, CHAIN_APPROX_NONE)`` in
  the C++) are exactly the zone pixels with a 4-neighbour outside the zone
  (image border counts as outside); the tests check this equivalence, and it
  lets all contacts be computed at once with array operations.
* Iteration order follows boost ``listS``: vertices in insertion order (zone
  ids, i.e. raster order of each zone's first pixel), and each vertex's
  neighbours in edge insertion order. Initial edges are inserted in the
  raster order of their first contact (a pixel compared with its left, then
  its upper neighbour); edges created by a fusion are appended.
* Edge minima: when z is fused into B, a *new* edge (B, n) records
  ``min(value(z), minimum of (z, n))``; an edge (B, n) that already existed is
  a direct contact and keeps its minimum (none). Every step's fusions record
  them, but only those present when :func:`mark_unbreakable_edges` runs
  matter. Also lowering existing edges' minima (a literal reading of the
  design notes) makes nearly every edge unbreakable and matched the released
  region counts far worse (24 instead of 40 of 57 exact, measured with the
  earlier watershed reading).
* Watershed flood (:func:`watershed_merge`): the recursion scans all
  neighbours of a zone, marking them visited (also those behind an
  unbreakable edge), before recursing into the ones it absorbed; closeNeigh
  only looks through breakable edges. The earlier depth-first reading (a
  zone behind an unbreakable edge stays absorbable through another path;
  closeNeigh over all edges) matched 40 instead of 43 of the 57 released
  region counts and gave the model 5 regions instead of 6.
* Fidelity, measured against the region counts of the released C++
  (``released_code_results.md``: 18 KTH sketches + the model, three
  parameter sets, 57 runs): 43 equal, 52 within +-1, all 57 within +-2. The free
  pixels left unlabelled match the authors' label images to within a few
  pixels per map.

Presets
-------
``PRESETS`` holds the parameter sets met in the original code and one chosen
by measurement for sketches:

=================  =====  =====  ==========================================
name               t      doors  origin
=================  =====  =====  ==========================================
``default``        0.25   40     GraphZone defaults; GT correspondences
                                 were clicked on these segmentations
``robot``          0.50   40     URSIM driver, robot maps
``ursim-released`` 0.50   40     = robot (the released driver used it for
                                 sketches too, ``is_sketch = false``)
``icra``           0.30   40     MAORIS paper evaluation
``sketch``         0.25   50     best single preset measured on sketches
                                 (see below)
=================  =====  =====  ==========================================

Measurement behind ``sketch``: the 18 sketches of
``maoris_segmentation/sketches/maps`` (free = grey > 250), scored with
:func:`ursim_core.segmentation.scoring.score_segmentation` against both
annotators; mean over sketches of P, R, F1 (``evF1``: the C++ evaluator's
per-predicted-region precision). ``authors`` = their label images
``maoris_output/NN.png`` scored the same way. Reproduce with
``ursim_core.bench.segmentation.bench_quality``::

    preset          gt_lex P/R/F1      gt_ezvin P/R/F1    mean F1  evF1 lex/ezvin
    authors         .693 .901 .777     .599 .911 .713     .745     .895 .883
    t=0.25 doors 40 .665 .893 .759     .572 .909 .696     .727     .883 .878
    t=0.25 doors 50 .712 .891 .788     .608 .904 .719     .753     .891 .883  <- sketch
    t=0.25 doors 60 .720 .889 .792     .615 .904 .725     .758     .890 .884
    t=0.30 doors 40 .640 .898 .743     .551 .914 .681     .712     .883 .877
    t=0.30 doors 60 .691 .896 .777     .591 .909 .708     .742     .890 .883
    t=0.35 doors 40 .630 .904 .739     .541 .917 .672     .705     .884 .877
    t=0.35 doors 60 .668 .900 .763     .572 .912 .694     .729     .887 .881
    t=0.40 doors 40 .592 .912 .713     .512 .923 .652     .682     .880 .874
    t=0.40 doors 60 .617 .910 .729     .533 .921 .668     .699     .882 .878
    t=0.50 doors 40 .541 .923 .675     .470 .932 .615     .645     .877 .870
    t=0.50 doors 60 .549 .922 .681     .478 .931 .621     .651     .877 .870

``sketch`` uses doors 50 rather than the slightly higher-scoring 60: a square
door passage (as long as it is wide) touches other regions on 52-56 % of its
contour, so doors 60 leaves such passages as regions of their own, which the
matcher then has to place; 50 fuses them and still beats the authors' label
images on both ground truths. Outside the grid, t=0.20 with doors 80 reaches
mean F1 .789 but over-segments (lower precision per predicted region on the
robot maps below).

The 15 robot maps of ``maoris_segmentation/robot_maps`` (free = grey > 250)
against ``gt``, same measure::

    preset          P    R    F1   evF1
    robot (t=0.50)  .811 .955 .857 .948
    default (0.25)  .919 .942 .925 .956
    icra (0.30)     .899 .946 .914 .956
    t=0.25 doors 60 .920 .942 .925 .954
    t=0.40 doors 40 .865 .951 .896 .956
    t=0.20 doors 80 .930 .938 .928 .925

Speed: the inscribed-circle image is exact and fast: only non-dominated
centres are painted (a few % of the free pixels), in compiled code, a ridge of
equal radii as one shape and a room corner's chain of growing discs only where
the next larger disc leaves them uncovered. On a 4000 px building (14 million
pixels) the painting takes about 0.1 s of CPU, less than the distance
transform (0.5 s), instead of 1.7 s with one ``cv2.circle`` per centre. The
graph steps follow the C++'s sequential order at a fraction of a microsecond
per flat zone; ripple merging, which updates contact counts around every
fusion, is the slowest step (about half the time on large maps, see the
README's speed table).

Examples
--------
>>> import numpy as np
>>> free = np.zeros((40, 80), bool)
>>> free[2:38, 2:38] = free[2:38, 42:78] = True   # two rooms
>>> free[18:22, 38:42] = True                     # and a door between them
>>> labels = maoris_labels(free)
>>> int(labels.max())
2
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.segmentation import _disc_kernels
from ursim_core.segmentation import _zone_kernels as _kernels

__all__ = [
    "MaorisParams",
    "PRESETS",
    "maoris_labels",
    "compile_kernels",
    "inscribed_circle_radii",
    "inscribed_circle_image",
    "quantize",
    "flat_zones",
    "ZoneGraph",
    "ZoneEdge",
    "remove_small_zones",
    "merge_ripples",
    "mark_unbreakable_edges",
    "watershed_merge",
    "remove_doors",
    "remove_isolated_zones",
]


# ---------------------------------------------------------------------------
# Parameters


@dataclass(frozen=True)
class MaorisParams:
    """Parameters of the MAORIS segmentation (GraphZone defaults).

    Attributes
    ----------
    threshold : float
        Watershed relative-difference threshold t in [0, 1); also the
        unbreakable-edge test ``min <= max(va, vb) * (1 - t)``.
    margin : float
        Extra tolerance of the watershed when a close neighbour exists, in [0, 1).
    ripples : float
        Percent of a zone's contour touching a neighbour that makes it a
        ripple of that neighbour, in [0, 100].
    doors : float
        Percent (summed over neighbours) of a region's contour touching other
        regions above which it is a door and is fused, >= 0.
    max_radius : int
        Largest inscribed-disc radius considered, px (>= 1).
    quantum : int
        Values are rounded up to multiples of this (1..255).
    small_before : int
        Zones smaller than this (px) are fused before ripple merging.
    small_after : int
        Regions smaller than this (px) are fused after door removal.

    Examples
    --------
    >>> MaorisParams().threshold
    0.25
    >>> MaorisParams().with_overrides(doors=60).doors
    60
    """

    threshold: float = 0.25
    margin: float = 0.10
    ripples: float = 40
    doors: float = 40
    max_radius: int = 500
    quantum: int = 5
    small_before: int = 10
    small_after: int = 100

    def __post_init__(self) -> None:
        for name, (kind, low, high, high_open) in _PARAM_RULES.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ParameterError(f"must be a number, got {value!r}", field=name)
            if kind is int and float(value) != int(value):
                raise ParameterError(f"must be an integer, got {value!r}", field=name)
            if (
                not math.isfinite(float(value))
                or value < low
                or (high is not None and (value >= high if high_open else value > high))
            ):
                bound = "" if high is None else (f" and < {high}" if high_open else f" and <= {high}")
                raise ParameterError(f"must be >= {low}{bound}, got {value!r}", field=name)
            # Store plain Python numbers so to_dict() is JSON-serialisable.
            object.__setattr__(self, name, int(value) if kind is int else _plain_number(value))

    def to_dict(self) -> dict[str, Any]:
        """Parameters as a JSON-serialisable dict.

        Examples
        --------
        >>> MaorisParams().to_dict()["doors"]
        40
        """
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> MaorisParams:
        """Build parameters from a dict; missing names take the defaults.

        Raises
        ------
        ParameterError
            For an unknown name or an invalid value (the message names it).

        Examples
        --------
        >>> MaorisParams.from_dict({"threshold": 0.5}).threshold
        0.5
        """
        return cls().with_overrides(**dict(values))

    def with_overrides(self, **overrides: Any) -> MaorisParams:
        """Copy with some parameters replaced, validating names and values.

        Examples
        --------
        >>> PRESETS["robot"].with_overrides(margin=0.2).margin
        0.2
        """
        known = {f.name for f in dataclasses.fields(self)}
        for name in overrides:
            if name not in known:
                raise ParameterError(f"unknown MAORIS parameter (known: {', '.join(sorted(known))})", field=str(name))
        return dataclasses.replace(self, **overrides)


def _plain_number(value: Any) -> int | float:
    value = float(value)
    return int(value) if value.is_integer() and abs(value) < 2**53 else value


# name -> (kind, minimum, maximum or None, maximum excluded)
_PARAM_RULES: dict[str, tuple[type, float, float | None, bool]] = {
    "threshold": (float, 0.0, 1.0, True),
    "margin": (float, 0.0, 1.0, True),
    "ripples": (float, 0.0, 100.0, False),
    "doors": (float, 0.0, None, False),
    "max_radius": (int, 1, None, False),
    "quantum": (int, 1, 255, False),
    "small_before": (int, 0, None, False),
    "small_after": (int, 0, None, False),
}

PRESETS: dict[str, MaorisParams] = {
    "default": MaorisParams(),
    "robot": MaorisParams(threshold=0.50, doors=40),
    "ursim-released": MaorisParams(threshold=0.50, doors=40),
    "icra": MaorisParams(threshold=0.30, doors=40),
    # Measured best on the sketch segmentation ground truth (module docstring).
    "sketch": MaorisParams(threshold=0.25, doors=50),
}


# ---------------------------------------------------------------------------
# Step 1: largest inscribed circle ("fuzzy opening")


def _as_free_mask(free: Any) -> np.ndarray:
    array = np.asarray(free)
    if array.ndim != 2 or array.shape[0] == 0 or array.shape[1] == 0:
        raise SegmentationError(f"free-space mask must be a non-empty 2-D array, got shape {array.shape}")
    return array.astype(bool, copy=False) if array.dtype != bool else array


def inscribed_circle_radii(free: np.ndarray, *, max_radius: int = 500) -> np.ndarray:
    """Radius of the largest (shifted) inscribed disc containing each free pixel.

    Exactly the C++ ``fuzzyOpening(src, out, max_radius)`` before normalisation:
    ``out(p) = max r(q)`` over free pixels q with ``|p - (q - (1, 1))| <= r(q) - 1``,
    where ``r(q) = min(int(dist(q)), max_radius)`` and dist is the exact
    Euclidean distance to the nearest obstacle pixel. Obstacle pixels get 0, and
    so do the free pixels no disc reaches (the row/column just above/left of a
    wall, an effect of the C++'s one-pixel shift).

    Instead of painting a disc per pixel, only the *non-dominated* centres are
    painted: q is dominated when a neighbour q2's disc contains q's disc
    (``r(q2) - r(q) >= |q2 - q|``), which removes ~95 % of them. The rest are
    painted row span by row span in compiled code (``_disc_kernels``), each
    pixel keeping the largest radius: equal-radius rectangles of centres
    (ridges) as one shape, and lone centres only where no disc of a larger
    radius beside them covers theirs.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True for free space.
    max_radius : int, keyword-only
        Cap on the disc radius (the C++ hard-codes 500).

    Returns
    -------
    ndarray of int32, shape (rows, cols)

    Examples
    --------
    >>> free = np.zeros((9, 9), bool); free[1:8, 1:8] = True
    >>> inscribed_circle_radii(free)[4]
    array([0, 4, 4, 4, 4, 4, 3, 0, 0], dtype=int32)
    """
    free = _as_free_mask(free)
    if int(max_radius) < 1:
        raise ParameterError(f"must be >= 1, got {max_radius!r}", field="max_radius")
    out = np.zeros(free.shape, np.int32)
    window = _free_bbox(free, margin=1)
    if window is None:
        return out
    out[window] = _inscribed_radii_in_window(free[window], int(max_radius))
    return out


def _free_bbox(free: np.ndarray, *, margin: int) -> tuple[slice, slice] | None:
    """Bounding box of the free pixels grown by ``margin`` (clipped), or None."""
    rows = np.flatnonzero(free.any(axis=1))
    if len(rows) == 0:
        return None
    cols = np.flatnonzero(free.any(axis=0))
    return (
        slice(max(rows[0] - margin, 0), min(rows[-1] + 1 + margin, free.shape[0])),
        slice(max(cols[0] - margin, 0), min(cols[-1] + 1 + margin, free.shape[1])),
    )


def _inscribed_radii_in_window(free: np.ndarray, max_radius: int) -> np.ndarray:
    # Cropping to the free pixels' bounding box plus a 1-pixel obstacle margin
    # leaves the distance transform unchanged (the margin is obstacle, and the
    # image border is kept where the box touches it).
    dist = cv2.distanceTransform(free.view(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    # Radii are int32 (as the output); a larger cap only matters without any obstacle.
    shapes = _disc_kernels.centre_rectangles(dist, min(max_radius, np.iinfo(np.int32).max))
    out = np.zeros(free.shape, np.int32)
    _disc_kernels.paint_discs(dist, shapes, out)
    return out


def _normalise_to_uint8(values: np.ndarray) -> np.ndarray:
    return _by_lookup(values, _normalise_exactly)


def _normalise_exactly(values: np.ndarray) -> np.ndarray:
    # cv::normalize(NORM_MINMAX, CV_8U) on a float image, as the C++ does.
    return cv2.normalize(np.asarray(values, np.float32), None, 0, 255, cv2.NORM_MINMAX, cv2.CV_8U)


def _by_lookup(values: np.ndarray, function) -> np.ndarray:
    """``function(values)`` for a ``function`` that maps each element by the
    element and the array's minimum and maximum only (a min-max normalisation).

    An integer image is mapped through a table: ``function`` of the range
    lo..hi of its values, which has the same minimum and maximum. At 4000 px
    that is one pass over the image instead of several float passes.
    """
    values = np.asarray(values)
    if values.dtype.kind not in "iu" or values.ndim != 2 or values.size == 0:
        return function(values)
    lo, hi = int(values.min()), int(values.max())
    if hi - lo > 1 << 16:
        return function(values)
    table = function(np.arange(lo, hi + 1, dtype=values.dtype)[None, :])[0]
    offsets = values - lo if lo else values
    if hi - lo <= 255:  # cv2.LUT takes 8-bit indices, and is several times faster than numpy
        return cv2.LUT(offsets.astype(np.uint8, copy=False), np.pad(table, (0, 255 - (hi - lo))))
    return table[offsets]


def inscribed_circle_image(free: np.ndarray, *, max_radius: int = 500) -> np.ndarray:
    """Largest-inscribed-circle image, min-max normalised to 0..255 (uint8).

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
    max_radius : int, keyword-only

    Returns
    -------
    ndarray of uint8
        0 on obstacles; the largest radius maps to 255.

    Examples
    --------
    >>> free = np.zeros((9, 9), bool); free[1:8, 1:8] = True
    >>> int(inscribed_circle_image(free).max())
    255
    """
    return _normalise_to_uint8(inscribed_circle_radii(free, max_radius=max_radius))


# ---------------------------------------------------------------------------
# Step 2: quantisation


def quantize(values: np.ndarray, *, quantum: int = 5) -> np.ndarray:
    """Min-max normalise to 0..255, then round up to multiples of ``quantum``.

    0 stays 0 (walls); results above 255 are clipped to 255.

    Parameters
    ----------
    values : ndarray
    quantum : int, keyword-only

    Returns
    -------
    ndarray of uint8

    Examples
    --------
    >>> quantize(np.array([[0, 1, 5, 6, 254, 255]], np.uint8)).tolist()
    [[0, 5, 5, 10, 255, 255]]
    """
    quantum = int(quantum)
    if not 1 <= quantum <= 255:
        raise ParameterError(f"must be in 1..255, got {quantum!r}", field="quantum")

    def exactly(values: np.ndarray) -> np.ndarray:
        normalised = _normalise_exactly(values).astype(np.int32)
        return np.minimum(-(-normalised // quantum) * quantum, 255).astype(np.uint8)

    return _by_lookup(values, exactly)


# ---------------------------------------------------------------------------
# Step 3: flat zones and the zone graph


def flat_zones(values: np.ndarray) -> np.ndarray:
    """4-connected components of equal non-zero value.

    Zones are numbered 1..N in the raster order of their first pixel; 0 stays 0.

    Examples
    --------
    >>> flat_zones(np.array([[5, 5, 0], [0, 5, 7], [5, 0, 7]])).tolist()
    [[1, 1, 0], [0, 1, 2], [3, 0, 2]]
    """
    values = np.asarray(values)
    if values.ndim != 2:
        raise SegmentationError(f"value image must be 2-D, got shape {values.shape}")
    return _kernels.label_flat_zones(values)


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
    ``_zone_kernels``): a large map starts with millions of flat zones, and
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
        self.shape = zones.shape
        zones = zones.astype(np.int32, copy=False)
        self._labels = np.pad(zones, _PAD)
        count = int(zones.max(initial=0))
        value, self._size = _kernels.zone_values_and_sizes(zones, values, count + 1)
        self._value_array = value
        self._value: list[int] = value.tolist()
        # The adjacency lives either in compact arrays (the compiled steps'
        # form, cheap for millions of zones) or in `_adj` dicts (see `adj`).
        self._alive = self._size > 0
        self._alive[0] = False
        self._compact: tuple | None = _kernels.build_adjacency(zones, value)
        self._adj: dict[int, dict[int, ZoneEdge | None]] | None = None
        # Contact counts, computed for the whole image when first queried and
        # dropped by the next fusion (the compiled steps track their own).
        self._contacts: dict[int, int] | None = None
        # Fusions not yet written into the label image: zone -> receiver (0 = deleted).
        self._pending: dict[int, int] = {}
        self._identity = np.arange(count + 1, dtype=np.int32)

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
        for zone, other, node, twin, low, unbreakable in _kernels.adjacency_entries(
            self._alive, self._compact
        ).tolist():
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
                (a, b, _kernels.NO_MINIMUM if edge is None or edge.minimum is None else edge.minimum,
                 edge is not None and edge.unbreakable)
                for a, neighbours in self._adj.items()
                for b, edge in neighbours.items()
            ]  # fmt: skip
            columns = list(zip(*entries)) or [()] * 4
            zone, other, minimum = (np.array(column, np.int32) for column in columns[:3])
            unbreakable = np.array(columns[3], bool)
            self._compact = _kernels.adjacency_from_entries(zone, other, minimum, unbreakable, self._value_array)
            self._alive = np.zeros(len(self._value), bool)
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
        return self._value[zone]

    def size(self, zone: int) -> int:
        """Number of pixels of a zone."""
        return int(self._size[zone])

    @property
    def labels(self) -> np.ndarray:
        """Current zone label image, shape ``self.shape`` (a view; do not modify)."""
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
        key = zone * len(self._value)
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
        self._flush()
        zones = np.array(self.vertices(), np.int64)
        # The padding adds no labels, so raster order in it is raster order in the map.
        first = _kernels.first_pixels(self._labels, len(self._value))[zones]
        lookup = np.zeros(len(self._value), np.int32)
        lookup[zones[np.argsort(first, kind="stable")]] = np.arange(1, len(zones) + 1, dtype=np.int32)
        return lookup[self.labels]

    # -- contacts and relabelling -------------------------------------------

    def _flush(self) -> None:
        """Write the pending fusions into the label image, in one vectorised pass."""
        if not self._pending:
            return
        pending = self._pending
        zones = np.fromiter(pending.keys(), np.int64, len(pending))
        # A persistent identity lookup, patched for this flush: allocating one per
        # flush would cost O(zones) each time.
        parent = self._identity
        parent[zones] = np.fromiter(pending.values(), np.int64, len(pending))
        # Follow chains z -> b -> c so every pending zone maps to its final
        # receiver: pointer doubling, log(chain length) vectorised passes.
        while True:
            jumped = parent[parent[zones]]
            if np.array_equal(jumped, parent[zones]):
                break
            parent[zones] = jumped
        self._labels = parent[self._labels]
        parent[zones] = zones
        self._pending = {}

    def _ensure_contacts(self) -> dict[int, int]:
        # Counts keyed by ``a * base + b``: contour pixels of a with b in their
        # 3x3 neighbourhood (b >= 1), and the contour size of a (b = 0).
        if self._contacts is None:
            self._flush()
            alive = np.zeros(len(self._value), bool)
            alive[self.vertices()] = True
            table = _kernels.contact_table(self._labels.ravel(), self._labels.shape[1], alive)
            codes = table[:, 0] * len(self._value) + table[:, 1]
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
        zone_value = self._value[zone]
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


# ---------------------------------------------------------------------------
# Steps 4-7: graph operations (each modifies the graph in place and returns it)


def remove_small_zones(graph: ZoneGraph, *, min_size: int) -> ZoneGraph:
    """Fuse every zone smaller than ``min_size`` px into its closest-valued neighbour.

    One pass in vertex order, sizes as they are when a zone is visited; ties
    go to the first neighbour; a small zone without neighbours is deleted.
    Fusions transfer edges as :meth:`ZoneGraph.fuse` does.

    Examples
    --------
    >>> values = np.array([[10, 10, 10, 30]], np.uint8)
    >>> graph = remove_small_zones(ZoneGraph(flat_zones(values), values), min_size=2)
    >>> graph.labels.tolist()
    [[1, 1, 1, 1]]
    """
    compact = graph._run_compiled()
    parent = np.where(graph._alive, np.arange(len(graph._value), dtype=np.int32), 0).astype(np.int32)
    _kernels.remove_small_zones(int(min_size), graph._size, graph._alive, parent, compact)
    _kernels.resolve_parents(parent, graph._alive)
    _kernels.relabel(graph._labels, parent)
    return graph


def merge_ripples(graph: ZoneGraph, *, ripples: float = 40) -> ZoneGraph:
    """Fuse ripple zones into the neighbour they wrap (``removeRiplesv3``).

    A zone z is a ripple of a neighbour B when ``contact_percent(z, B) >=
    ripples``. Zones are visited by decreasing value (smaller size first on
    ties, then by id); a ripple is fused into the candidate B of closest value
    (the first on ties) reached through a breakable edge, and its neighbours
    are queued again.

    Examples
    --------
    >>> values = np.full((7, 7), 100, np.uint8); values[2:5, 2:5] = 200
    >>> graph = merge_ripples(ZoneGraph(flat_zones(values), values))
    >>> len(graph)   # the ring touches the core on >= 40 % of its contour
    1
    """
    compact = graph._run_compiled()
    zones = np.flatnonzero(graph._alive)
    order = zones[np.lexsort((graph._size[zones], -graph._value_array[zones]))].astype(np.int32)
    labels, width = graph._labels.ravel(), graph._labels.shape[1]
    tracking = _kernels.start_tracking(labels, width, graph._alive)
    _kernels.merge_ripples(order, float(ripples), labels, width, graph._size, graph._alive, compact, tracking)
    return graph


def mark_unbreakable_edges(graph: ZoneGraph, *, threshold: float) -> ZoneGraph:
    """Make an edge unbreakable if its recorded minimum is a deep enough valley.

    An edge (a, b) that carries a minimum becomes unbreakable when
    ``minimum <= max(value(a), value(b)) * (1 - threshold)``.
    """
    for a in graph.vertices():
        for b, edge in graph.adj[a].items():
            if (
                edge is not None
                and edge.minimum is not None
                and edge.minimum <= max(graph.value(a), graph.value(b)) * (1 - threshold)
            ):
                edge.unbreakable = True
    return graph


def _similar(a: int, b: int, threshold: float) -> bool:
    high, low = (a, b) if a >= b else (b, a)
    return low >= high * (1 - threshold)


def _close_neighbour(graph: ZoneGraph, current: int, candidate: int, threshold: float) -> bool:
    # closeNeigh: another neighbour of one of the two, reached through a
    # breakable edge (the only edges the watershed looks through), is within t
    # of the other one.
    value_current, value_candidate = graph.value(current), graph.value(candidate)
    for one, other_value, skip in ((candidate, value_current, current), (current, value_candidate, candidate)):
        for m, edge in graph.adj[one].items():
            if (
                m != skip
                and (edge is None or not edge.unbreakable)
                and _similar(graph.value(m), other_value, threshold)
            ):
                return True
    return False


def watershed_merge(graph: ZoneGraph, *, threshold: float, margin: float = 0.10) -> ZoneGraph:
    """Merge neighbouring zones of similar value into the highest one (``watershed``).

    Tops are visited by decreasing value (larger size first on ties). The
    flood from a top is the C++ recursion: a call on zone c first scans all
    of c's neighbours in edge order, marking each one not yet visited as
    visited, *whether its edge is breakable or not*; a neighbour reached
    through a breakable edge is absorbed if, with hi/lo the values of c and
    the neighbour, ``lo >= hi * (1 - t)``, or if ``lo >= hi * (1 - t -
    margin)`` and another neighbour of one of the two, through a breakable
    edge, is within t of the other. Only then does the recursion run on the
    zones absorbed from c, in that order. So a zone met first across an
    unbreakable edge, or rejected once, is not absorbed through another path
    of the same flood (a later top may still take it). All absorptions are
    decided on the graph as it was at the start, then fused.

    Examples
    --------
    >>> values = np.array([[200, 200, 180, 180, 60, 60]], np.uint8)
    >>> graph = watershed_merge(ZoneGraph(flat_zones(values), values), threshold=0.25)
    >>> graph.labels.tolist()
    [[1, 1, 1, 1, 3, 3]]
    """
    order = sorted(graph.vertices(), key=lambda zone: (-graph.value(zone), -graph.size(zone)))
    absorbed: set[int] = set()
    groups: list[tuple[int, list[int]]] = []
    low_factor = 1 - threshold - margin
    for top in order:
        if top in absorbed:
            continue
        absorbed.add(top)
        visited = {top}
        members: list[int] = []
        # Stack of the zones still to expand, one list per scanned zone (the
        # recursion of the C++, without Python's recursion limit).
        stack = [iter([top])]
        while stack:
            current = next(stack[-1], None)
            if current is None:
                stack.pop()
                continue
            taken = []
            for neighbour, edge in graph.adj[current].items():
                if neighbour in visited or neighbour in absorbed:
                    continue
                visited.add(neighbour)
                if edge is not None and edge.unbreakable:
                    continue
                a, b = graph.value(current), graph.value(neighbour)
                high, low = max(a, b), min(a, b)
                if low >= high * (1 - threshold) or (
                    low >= high * low_factor and _close_neighbour(graph, current, neighbour, threshold)
                ):
                    absorbed.add(neighbour)
                    members.append(neighbour)
                    taken.append(neighbour)
            if taken:
                stack.append(iter(taken))
        if members:
            groups.append((top, members))
    for top, members in groups:
        for member in members:
            graph.fuse(member, top)
    return graph


def remove_doors(graph: ZoneGraph, *, doors: float = 40) -> ZoneGraph:
    """Fuse door-like regions, whose contour mostly touches other regions (``removeDoors``).

    A region whose contact sum (:meth:`ZoneGraph.contact_sum`) exceeds ``doors``
    is fused into the last neighbour whose own sum is below ``doors``, else into
    its first neighbour; the receiver's sum is then recomputed. Zones are
    visited in id order, with the sums taken before the first fusion except
    for receivers. Runs compiled, tracking contacts as :func:`merge_ripples`.

    Examples
    --------
    >>> values = np.zeros((12, 24), np.uint8)
    >>> values[1:11, 1:11] = values[1:11, 13:23] = 200   # two rooms
    >>> values[4:8, 11:13] = 50                           # a door
    >>> graph = ZoneGraph(flat_zones(values), values)
    >>> graph.contact_sum(3), remove_doors(graph).vertices()
    (100, [1, 2])
    """
    compact = graph._run_compiled()
    labels, width = graph._labels.ravel(), graph._labels.shape[1]
    tracking = _kernels.start_tracking(labels, width, graph._alive)
    _kernels.remove_doors(float(doors), labels, width, graph._size, graph._alive, compact, tracking)
    return graph


def remove_isolated_zones(graph: ZoneGraph) -> ZoneGraph:
    """Delete zones without neighbours, when there is more than one zone
    (``removeLonelyVertices``).

    Examples
    --------
    >>> values = np.array([[10, 0, 20, 30]], np.uint8)
    >>> remove_isolated_zones(ZoneGraph(flat_zones(values), values)).vertices()
    [2, 3]
    """
    if len(graph) > 1:
        for zone in graph.vertices():
            if not graph.adj[zone]:
                graph.remove(zone)
    return graph


# ---------------------------------------------------------------------------
# Whole pipeline


def maoris_labels(free: np.ndarray, params: MaorisParams = PRESETS["default"]) -> np.ndarray:
    """Segment a free-space mask into rooms with MAORIS.

    Parameters
    ----------
    free : ndarray of bool, shape (rows, cols)
        True = free space.
    params : MaorisParams
        See :data:`PRESETS`.

    Returns
    -------
    ndarray of int32
        0 = no region; regions 1..N in the raster order of their first pixel.

    Notes
    -----
    As in the C++, some free pixels get no region: the row and column just
    above and left of walls (the one-pixel shift of the inscribed discs),
    regions deleted for having no neighbour when there are several, and
    everything when the map has no obstacle pixel at all (the inscribed-circle
    image is then constant and normalises to 0). A map without free pixels
    gives all zeros.

    Examples
    --------
    >>> free = np.zeros((30, 30), bool); free[3:27, 3:27] = True
    >>> int(maoris_labels(free, PRESETS["robot"]).max())
    1
    """
    if not isinstance(params, MaorisParams):
        raise ParameterError(f"expected MaorisParams, got {type(params).__name__}", field="params")
    free = _as_free_mask(free)
    labels = np.zeros(free.shape, np.int32)
    # Everything outside the free pixels' bounding box is obstacle: work on the box.
    window = _free_bbox(free, margin=1)
    if window is None:
        return labels
    free = free[window]
    values = quantize(inscribed_circle_image(free, max_radius=params.max_radius), quantum=params.quantum)
    graph = ZoneGraph(flat_zones(values), values)
    remove_small_zones(graph, min_size=params.small_before)
    merge_ripples(graph, ripples=params.ripples)
    mark_unbreakable_edges(graph, threshold=params.threshold)
    watershed_merge(graph, threshold=params.threshold, margin=params.margin)
    remove_doors(graph, doors=params.doors)
    remove_small_zones(graph, min_size=params.small_after)
    remove_isolated_zones(graph)
    labels[window] = graph.label_image()
    return labels


def compile_kernels() -> float:
    """Compile (or load from numba's cache) the compiled steps; return the seconds it took.

    The first segmentation in a new environment otherwise pays this (about
    43 s; under a second once cached). Benchmarks call it
    so that their timings exclude it.

    Examples
    --------
    >>> compile_kernels() >= 0
    True
    """
    import time

    start = time.perf_counter()
    free = np.zeros((40, 60), bool)
    free[3:37, 3:28] = free[3:37, 31:57] = free[15:22, 28:31] = True  # two rooms and a door
    labels = maoris_labels(free, PRESETS["default"])
    # Large images count contacts in bands of rows, which this small one does not.
    padded = np.pad(labels, _PAD)
    alive = np.arange(int(labels.max()) + 1) > 0
    _kernels.start_tracking(padded.ravel(), padded.shape[1], alive, bands=2)
    return time.perf_counter() - start
