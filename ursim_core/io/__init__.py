"""Reading and writing files: map images, ROS map_server YAML, atomic writes.

Owns: :class:`Map` and its loaders (:func:`load_map`, :func:`map_from_array`), the pixel <->
world conversions, and :func:`atomic_write_bytes` / :func:`atomic_write_text`, which every
save of the project goes through.

Modules: ``maps`` (the Map value, load_map, map_from_array, pixel <-> world), ``images``
(file bytes -> decoded pixels -> grey), ``ros_yaml`` (ROS map_server YAML, as nav2 reads it),
``occupancy_grid`` (ROS OccupancyGrid messages in and out), ``map_saver`` (a map_server YAML and
its image, as nav2's map_saver writes them),
``reading`` (bounded reads of regular files only: no pipe, device or multi-GB file),
``atomic`` (atomic writes; stale temporary files cleaned).

May import: :mod:`ursim_core.errors` only. Everything else builds on it.

>>> from ursim_core.io import map_from_array
>>> import numpy as np
>>> map_from_array(np.full((4, 5), 255, np.uint8)).shape
(4, 5)
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["atomic", "images", "map_saver", "maps", "occupancy_grid", "reading", "ros_yaml"],
    submod_attrs={
        "atomic": ["atomic_write_bytes", "atomic_write_text"],
        "maps": [
            "Map",
            "load_map",
            "map_from_array",
            "pixel_to_world",
            "world_to_pixel",
            "DEFAULT_FREE_THRESHOLD",
            "DEFAULT_MAX_PIXELS",
            "OCCUPANCY_FREE",
            "OCCUPANCY_OCCUPIED",
            "OCCUPANCY_UNKNOWN",
        ],
        "occupancy_grid": [
            "OccupancyGrid",
            "map_from_occupancy_grid",
            "occupancy_grid_from_map",
            "occupancy_from_free",
            "yaw_from_quaternion",
            "quaternion_from_yaw",
        ],
        "map_saver": ["save_map_yaml", "SAVE_MODES", "SAVE_DEFAULTS"],
    },
)
