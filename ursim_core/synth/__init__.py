"""Generated floor plans, their sketches and their ground truth.

Owns: the floor-plan generator (:mod:`~ursim_core.synth.floor_plans`, with the large buildings of
the scale benchmark), ``sketchify`` (a plan drawn as a person would: wobbly walls, missing doors,
another scale; :mod:`~ursim_core.synth.drawing`), the exact ground-truth cliques of a generated
pair (:mod:`~ursim_core.synth.ground_truth`) and the bundled example pair
(:mod:`~ursim_core.synth.example`).

May import: :mod:`ursim_core.correspondences`, :mod:`ursim_core.io`, :mod:`ursim_core.errors`.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["drawing", "example", "floor_plans", "ground_truth"],
    submod_attrs={
        "floor_plans": ["Place", "FloorPlan", "generate_floor_plan", "make_large_building", "interior_points"],
        "drawing": ["Sketch", "sketchify"],
        "ground_truth": ["ground_truth_pairs", "ground_truth_correspondences"],
        "example": ["make_pair", "save_example"],
    },
)
