"""Segmentation of a map into regions, behind one small interface.

Owns: :class:`Segmentation` (label image + region adjacency graph), :func:`segment` and the
``SEGMENTERS`` registry, label-image files, the regions (:func:`region_table`, no networkx) and their graph
(:func:`region_graph`), MAORIS
(:mod:`ursim_core.segmentation.maoris`), the clearance watershed
(:mod:`ursim_core.segmentation.watershed`), learned merging of candidate pieces
(:mod:`ursim_core.segmentation.learned`, its figures :mod:`ursim_core.segmentation.learned_cv`), leave-one-map-out figures of the presets
(:mod:`ursim_core.segmentation.presets_cv`) and the scoring of a segmentation against ground truth
(:mod:`ursim_core.segmentation.scoring`).

May import: :mod:`ursim_core.io` and :mod:`ursim_core.errors`; never matching, evaluation or
anything above them.

>>> import numpy as np
>>> from ursim_core.segmentation import segment
>>> free = np.zeros((100, 160), bool)
>>> free[10:90, 10:70] = free[10:90, 90:150] = free[45:55, 70:90] = True  # two rooms, a corridor
>>> segment(free, preset="default").n_regions
3
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=[
        "interface",
        "label_files",
        "regions",
        "graph",
        "scoring",
        "maoris",
        "watershed",
        "presets_cv",
        "learned",
        "learned_cv",
    ],
    submod_attrs={
        "interface": [
            "Segmentation",
            "SEGMENTERS",
            "segment_canonical",
            "with_resamplings",
            "DEFAULT_SEGMENTERS",
            "segment",
            "resolve_params",
            "method_presets",
            "why_no_region",
        ],
        "label_files": ["read_label_array", "load_label_image", "save_label_image"],
        "regions": ["RegionTable", "region_table", "adjacent_pairs", "contour_pca_shape", "row_bands"],
        "graph": ["region_graph"],
        "watershed": ["watershed_labels"],
        "presets_cv": ["cross_validate"],
        "learned": ["learned_labels"],
        "learned_cv": ["cross_validate_learned"],
    },
)
