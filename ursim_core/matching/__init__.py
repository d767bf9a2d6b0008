"""Matching a sketch's regions to a metric map's regions.

Owns: the region descriptors (:mod:`~ursim_core.matching.descriptors`: attributes, uniqueness,
anchors, vertex-weighted Laplacian, heat-kernel signatures), the configuration
(:class:`MatchConfig`), the seed-and-expand planar matcher (:mod:`~ursim_core.matching.planar`),
the baselines (Hungarian, VF2), the automatic choice of the threshold m, and the whole pipeline
from two maps (:func:`match_maps`: each map segmented as the matcher expects, then matched).

May import: :mod:`ursim_core.segmentation` (values; its segmenters in ``from_maps`` only), :mod:`ursim_core.io`,
:mod:`ursim_core.errors`. Scoring against ground truth lives in :mod:`ursim_core.evaluation`.

>>> from ursim_core.matching import MatchConfig
>>> MatchConfig().matcher, MatchConfig().resolved().matcher  # a sketch: no known scale
('auto', 'planar')
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=[
        "auto_m",
        "baselines",
        "config",
        "constraints",
        "descriptors",
        "edit_distance",
        "from_maps",
        "lsap",
        "orientation",
        "pipeline",
        "planar",
        "results",
        "single",
    ],
    submod_attrs={
        # From config, not pipeline: a caller who only builds a configuration does not import
        # networkx and the matcher (29 ms instead of 379 ms).
        "config": ["MATCH_PRESETS", "M_GRID", "MATCHERS", "MatchConfig"],
        "from_maps": [
            "MapsMatch",
            "map_ref",
            "match_maps",
            "segment_for_matching",
            "segment_pair",
            "sketch_segmentation_rule",
        ],
        "pipeline": [
            "MatchResult",
            "Prepared",
            "prepare",
            "match_prepared",
            "match",
            "seed_pairs",
            "seed_cap",
            "pair_cost_matrix",
        ],
        "descriptors": ["DEFAULT_TIMES", "SIZE_WEIGHT_FLOOR", "VARIANTS", "PairDescriptors", "pair_descriptors"],
        "baselines": ["hungarian_match", "vf2_match"],
        "planar": ["PlanarGraph", "planar_graph", "planar_match"],
        "constraints": ["CONSTRAINED_MATCHERS", "MatchConstraints", "constraints_from_cliques", "pairs_beside_review"],
        "lsap": ["linear_sum_assignment"],
    },
)
