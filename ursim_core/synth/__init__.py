"""Generated floor plans, their sketches and their ground truth.

Owns: the floor-plan generator, ``sketchify`` (a plan drawn as a person would: wobbly walls,
missing doors, another scale), the ground-truth cliques of a generated pair, the large
buildings of the scale benchmark and the bundled example pair.

May import: :mod:`ursim_core.correspondences`, :mod:`ursim_core.io`, :mod:`ursim_core.errors`.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["generator"],
    submod_attrs={
        "generator": [
            "Place",
            "FloorPlan",
            "Sketch",
            "generate_floor_plan",
            "sketchify",
            "interior_points",
            "ground_truth_pairs",
            "ground_truth_correspondences",
            "make_pair",
            "make_large_building",
            "save_example",
        ],
    },
)
