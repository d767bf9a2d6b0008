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

:func:`maoris_labels` runs them all. Where each lives:

* :mod:`.params`: :class:`MaorisParams` and :data:`PRESETS` (and how the presets were chosen);
* :mod:`.inscribed_circle`: steps 1-2, the value image;
* :mod:`.zone_graph`: step 3, :func:`flat_zones` and :class:`ZoneGraph`;
* :mod:`.steps`: steps 4-7, the graph operations;
* :mod:`.pipeline`: :func:`maoris_labels`, :func:`compile_kernels`, :func:`kernels_cached`;
* :mod:`.kernels`: the compiled (numba) loops, one module per family;
* :mod:`.compiled`: the kernels as the steps call them (built ahead of time, or the JIT);
* :mod:`.contact_tracking`: counting contacts in bands of rows on threads.

Importing this package imports none of them (nor numba): each name loads its module on
first use.

Speed: a 4000 x 4000 map starts with about 1.5 million flat zones, visited
one by one in an order that decides ties, so the graph steps cannot be
vectorised; steps 3, 4 and 6 run as compiled code (numba, :mod:`.kernels`)
on an array form of the zone graph, and step 1 paints its discs with compiled
code too (:mod:`.kernels.discs`). The contacts of large maps are counted in bands
of rows on one thread per CPU. :func:`compile_kernels` builds the kernels once ahead of
time into extension modules (numba's ``pycc``, about 17 s on two CPUs; ``make`` runs it, and
the first segmentation does if nothing did), which later processes load in milliseconds
without importing numba; ``URSIM_KERNELS=jit`` uses numba's JIT and its cache instead
(``ursim bench compile`` measures both). :func:`kernels_cached` tells, without importing
numba, whether that is done.

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

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=[
        "params",
        "inscribed_circle",
        "zone_graph",
        "steps",
        "pipeline",
        "kernel_cache",
        "kernels",
        "compiled",
        "contact_tracking",
    ],
    submod_attrs={
        "params": ["MaorisParams", "PRESETS"],
        "inscribed_circle": ["inscribed_circle_radii", "inscribed_circle_image", "quantize"],
        "zone_graph": ["flat_zones", "ZoneGraph", "ZoneEdge"],
        "steps": [
            "remove_small_zones",
            "merge_ripples",
            "mark_unbreakable_edges",
            "watershed_merge",
            "remove_doors",
            "remove_isolated_zones",
        ],
        "pipeline": ["maoris_labels", "compile_kernels"],
        "kernel_cache": ["kernels_cached", "compile_notice", "COMPILE_SECONDS", "COMPILE_CPU_SECONDS"],
    },
)
