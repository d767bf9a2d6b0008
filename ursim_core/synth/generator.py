"""Where the synth functions lived before they were split by concern; kept so old imports work.

Import from :mod:`ursim_core.synth` (or its modules :mod:`~ursim_core.synth.floor_plans`,
:mod:`~ursim_core.synth.drawing`, :mod:`~ursim_core.synth.ground_truth`,
:mod:`~ursim_core.synth.example`) instead.
"""

from ursim_core.synth.drawing import Sketch, sketchify
from ursim_core.synth.example import make_pair, save_example
from ursim_core.synth.floor_plans import FloorPlan, Place, generate_floor_plan, interior_points, make_large_building
from ursim_core.synth.ground_truth import ground_truth_correspondences, ground_truth_pairs

__all__ = [
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
]
