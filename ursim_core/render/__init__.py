"""Pictures of results: segmentation overlays and side-by-side match figures (PNG, atomic).

May import: :mod:`ursim_core.io`, :mod:`ursim_core.errors` and :func:`ursim_core.segmentation.regions.row_bands`; it draws plain arrays and graphs.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["figures"],
    submod_attrs={
        "figures": [
            "FIGURE_MAX_SIDE",
            "distinct_colors",
            "label_colors",
            "overlay_segmentation",
            "side_by_side_matches",
            "save_png",
        ]
    },
)
