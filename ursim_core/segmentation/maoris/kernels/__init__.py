"""Compiled loops of MAORIS (numba), one module per family.

* :mod:`.helpers`: the decorator of the small inlined helpers, array growth, union-find, prefetch;
* :mod:`.distance`: the exact Euclidean distance transform, along rows (step 1);
* :mod:`.discs`: painting the inscribed discs (step 1);
* :mod:`.flat_zones`: flat-zone labelling, zone values and sizes, relabelling (step 3);
* :mod:`.adjacency`: the compact zone graph (records and twin nodes), edge transfer on a fusion,
  small-zone removal (steps 3, 4 and 7);
* :mod:`.contact_table`: the contact counts' storage (per-zone slots and a shared hash table);
* :mod:`.contacts`: counting contacts of a label image (in bands of rows on threads);
* :mod:`.fusion`: ripple merging and door removal, which track contacts across fusions (steps 4, 6);
* :mod:`.flooding`: the watershed's priority flood and clearance levels, for
  :mod:`ursim_core.segmentation.flooding` (they live here to be built ahead of time with the rest);
* :mod:`.signatures`: the one signature of each kernel called from Python, and compiling them.

The Python side, :class:`ursim_core.segmentation.maoris.zone_graph.ZoneGraph`, owns the arrays;
these functions only mutate them. Nothing here is public API.
"""
