"""Region correspondences (cliques) between a sketch and a metric map, and their files.

Owns: the value types (:class:`Clique`, :class:`MapRef`, :class:`Correspondences`), the JSON
codec with its schema (``schemas/correspondences-1.schema.json``; atomic saves, unknown keys
preserved), the original ``.dat`` codec, and the assignment of clicked points to regions.

Modules: ``values`` (the frozen value types), ``schema`` (JSON Schema, compiled validator,
readable schema errors), ``json_codec`` (load / save the JSON file; ``json_text`` writes its exact text), ``dat_codec`` (the
original ``.dat`` format), ``files`` (bounded reads; guarded atomic saves), ``assignment`` (points -> region ids). ``codec`` is the deprecated
old home of all of them, kept for one release.

May import: :mod:`ursim_core.io` and :mod:`ursim_core.errors` (label images are plain arrays
here, so it does not need :mod:`ursim_core.segmentation`).

>>> from ursim_core.correspondences import Clique
>>> Clique(id=1, sketch_points=[(3, 4)], metric_points=[(10, 12)]).sketch_points
((3, 4),)
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=[
        "values",
        "schema",
        "files",
        "json_text",
        "json_codec",
        "dat_codec",
        "assignment",
        "exporters",
        "codec",
    ],
    submod_attrs={
        "values": ["SOURCES", "STATUSES", "MapRef", "Clique", "Correspondences", "utc_timestamp"],
        "schema": ["FORMAT_NAME", "CURRENT_VERSION", "correspondences_schema"],
        "json_codec": [
            "SUPPORTED_VERSIONS",
            "check_maps",
            "load_correspondences",
            "load_correspondence_file",
            "save_correspondences",
            "correspondences_to_json",
        ],
        "dat_codec": ["load_dat", "save_dat"],
        "assignment": ["regions_at_points", "assign_regions", "from_pairs"],
        "exporters": [
            "EXPORT_FORMATS",
            "LABEL_KEY",
            "clique_label",
            "with_clique_label",
            "region_polygons",
            "correspondences_to_geojson",
            "correspondences_to_labelme",
            "correspondences_to_qgis_points",
            "export_correspondences",
            "export_format_of",
            "export_file",
        ],
    },
)
