"""URSIM Studio core: match hand-drawn sketch maps to metric maps.

Qt-free. Data flows one way::

    file --load_map--> Map --segment--> Segmentation (labels + region graph)
         --match--> MatchResult --> Correspondences (cliques) <--> JSON / .dat
         --evaluate--> precision / recall / F1 and place accuracy against reference cliques

Where each step lives (subpackages are imported on first use, so ``import ursim_core`` is cheap):

- :mod:`ursim_core.io`: ``load_map`` (PNG, PGM, ROS map_server YAML), ``map_from_array``,
  OccupancyGrid in and out, atomic writes;
- :mod:`ursim_core.segmentation`: ``segment`` (MAORIS, watershed), label images;
- :mod:`ursim_core.matching`: ``match_maps`` (two maps segmented as the matcher expects, then
  matched: what ``ursim match`` runs), ``match`` (two segmentations), ``MatchConfig``;
- :mod:`ursim_core.correspondences`: cliques, their JSON and ``.dat`` files, exports;
- :mod:`ursim_core.navigation`: ``locate`` (a sketch point to a goal in the robot's map), routes;
- :mod:`ursim_core.evaluation`: ``score_against_reference`` (F1 and place accuracy), datasets;
- :mod:`ursim_core.errors`: every error raised for bad input (``UrsimError`` and its kinds).

Pixel coordinates are always (row, col). The README's "The library" section walks from a sketch to
a goal.
"""

__version__ = "0.1.0"
