"""From sketch to robot: a tap or a drawn route on the sketch becomes goals in the robot's map.

Owns: :func:`locate` (sketch point -> goal: region, clique, metric pixel, world pose), the
:class:`MatchTable` it reads matches through, :func:`plan_route` (polyline -> connected metric
regions -> waypoints) and the nav2 files (:func:`pose_stamped`, the RViz panel's waypoint YAML).

May import: :mod:`ursim_core.matching` and below (segmentation, correspondences, io, errors).
:mod:`ursim_core.evaluation` calls :func:`locate` for place accuracy, so the score and the robot
use one rule.

>>> from ursim_core.navigation import match_table
>>> match_table([(1, 4)]).metric_of
{1: (4,)}
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["goal", "route", "nav2_files", "session"],
    submod_attrs={
        "goal": ["Goal", "NearestMatch", "MatchTable", "match_table", "locate", "clique_label", "LABEL_KEY", "TARGETS"],
        "route": ["Route", "Waypoint", "plan_route", "sample_polyline"],
        "session": ["NavigationSession", "NAVIGATION_FORMAT"],
        "nav2_files": [
            "pose_stamped",
            "waypoints_yaml",
            "save_waypoints_yaml",
            "load_waypoints_yaml",
            "quaternion_xyzw",
        ],
    },
)
