"""Region correspondences (cliques) between a sketch and a metric map, and their files.

Owns: the value types (:class:`Clique`, :class:`MapRef`, :class:`Correspondences`), the JSON
codec with its schema (``schemas/correspondences-1.schema.json``; atomic saves, unknown keys
preserved), the original ``.dat`` codec, and the assignment of clicked points to regions.

May import: :mod:`ursim_core.io` and :mod:`ursim_core.errors` (label images are plain arrays
here, so it does not need :mod:`ursim_core.segmentation`).

>>> from ursim_core.correspondences import Clique
>>> Clique(id=1, sketch_points=[(3, 4)], metric_points=[(10, 12)]).sketch_points
((3, 4),)
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["codec"],
    submod_attrs={
        "codec": [
            "FORMAT_NAME",
            "CURRENT_VERSION",
            "SUPPORTED_VERSIONS",
            "SOURCES",
            "STATUSES",
            "MapRef",
            "Clique",
            "Correspondences",
            "load_correspondences",
            "save_correspondences",
            "correspondences_to_json",
            "correspondences_schema",
            "load_dat",
            "save_dat",
            "regions_at_points",
            "assign_regions",
            "from_pairs",
            "utc_timestamp",
        ],
    },
)
