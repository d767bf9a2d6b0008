"""URSIM Studio core: match hand-drawn sketch maps to metric maps.

Qt-free. Data flows one way::

    file --load_map--> Map --segment--> Segmentation (labels + region graph)
         --match--> MatchResult --> Correspondences (cliques) <--> JSON / .dat
         --evaluate--> precision / recall / F1 against reference cliques

Pixel coordinates are always (row, col).
"""

__version__ = "0.1.0"
