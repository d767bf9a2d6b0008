"""ROS ``nav_msgs/OccupancyGrid`` in and out.

Conventions, as in nav2's ``map_io`` (``nav2_map_server/src/map_io.cpp``):

- An OccupancyGrid's ``data`` is row-major with cell (0, 0) at the map origin, i.e. the *bottom*
  row of the image comes first. :class:`~ursim_core.io.maps.Map` keeps row 0 at the top, so rows
  are flipped on the way in and out (``data[width * (height - row - 1) + col]`` is image pixel
  ``(row, col)``).
- Cell values: 0 free, 100 occupied, -1 unknown, 1..99 intermediate (scale mode). ``Map.free`` is
  ``occupancy == 0``: unknown (-1) and occupied (100) are obstacles for segmentation, as for
  YAML maps read by :func:`~ursim_core.io.maps.load_map`.
- The origin is the world pose of the lower-left corner of cell (0, 0); only its yaw is kept
  (a 2-D map), read from the quaternion as ``tf2::getYaw`` does.

The map_server YAML writer is :func:`ursim_core.io.map_saver.save_map_yaml`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.errors import MapError, ParameterError
from ursim_core.io.maps import OCCUPANCY_FREE, OCCUPANCY_OCCUPIED, OCCUPANCY_UNKNOWN, Map
from ursim_core.io.ros_yaml import world_extent_problem

__all__ = [
    "OccupancyGrid",
    "map_from_occupancy_grid",
    "occupancy_grid_from_map",
    "occupancy_from_free",
    "yaw_from_quaternion",
    "quaternion_from_yaw",
]

#: Grey values nav2's map_saver writes in trinary mode (free, occupied, unknown).
TRINARY_FREE, TRINARY_OCCUPIED, TRINARY_UNKNOWN = 254, 0, 205
# Largest roll or pitch (radians) accepted in an origin quaternion: a 2-D map lies flat.
_MAX_TILT = 1e-3


@dataclass(frozen=True, eq=False)
class OccupancyGrid:
    """The fields of a ``nav_msgs/OccupancyGrid``, without ROS.

    Attributes
    ----------
    data : ndarray of int8, shape (height * width,)
        Row-major cells, row 0 at the origin (the bottom of the image).
    width, height : int
        Cells per row, number of rows.
    resolution : float
        Metres per cell.
    origin : (float, float, float)
        (x, y, yaw) of the lower-left corner of cell (0, 0) in the frame ``frame_id``.
    frame_id : str
        The frame of the origin ("map").

    Examples
    --------
    >>> grid = OccupancyGrid(data=[0, 100, -1, 0], width=2, height=2, resolution=0.5, origin=(1.0, 2.0, 0.0))
    >>> grid.cells()
    array([[ -1,   0],
           [  0, 100]], dtype=int8)
    >>> grid.origin_quaternion()
    (0.0, 0.0, 0.0, 1.0)
    """

    data: np.ndarray
    width: int
    height: int
    resolution: float
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame_id: str = "map"
    extra: dict = field(default_factory=dict, repr=False)

    def __post_init__(self):
        width, height = _positive_int(self.width, "width"), _positive_int(self.height, "height")
        data = np.asarray(self.data)
        if data.ndim != 1 or data.size != width * height:
            raise MapError(f"OccupancyGrid data has {data.size} cells, expected width * height = {width * height}")
        if data.size and (int(data.min()) < -128 or int(data.max()) > 127):
            raise MapError("OccupancyGrid data must be int8 values (-1 unknown, 0..100)")
        object.__setattr__(self, "data", data.astype(np.int8))
        object.__setattr__(self, "width", width)
        object.__setattr__(self, "height", height)
        object.__setattr__(self, "resolution", _positive_float(self.resolution, "resolution"))
        origin = tuple(float(value) for value in self.origin)
        if len(origin) != 3 or not all(math.isfinite(value) for value in origin):
            raise MapError(f"origin must be (x, y, yaw), three finite numbers, got {self.origin!r}", field="origin")
        object.__setattr__(self, "origin", origin)
        extent_problem = world_extent_problem(self.resolution, origin, (height, width))
        if extent_problem is not None:
            raise MapError(f"OccupancyGrid: {extent_problem[1]}", field=extent_problem[0])

    def cells(self) -> np.ndarray:
        """The cells as an image: shape (height, width), row 0 at the *top* (rows flipped)."""
        return self.data.reshape(self.height, self.width)[::-1].copy()

    def origin_quaternion(self) -> tuple[float, float, float, float]:
        """The origin's orientation as (x, y, z, w)."""
        return quaternion_from_yaw(self.origin[2])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, OccupancyGrid):
            return NotImplemented
        return (
            (self.width, self.height, self.frame_id) == (other.width, other.height, other.frame_id)
            and math.isclose(self.resolution, other.resolution, rel_tol=1e-9)
            and all(math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12) for a, b in zip(self.origin, other.origin))
            and np.array_equal(self.data, other.data)
        )

    __hash__ = None  # type: ignore[assignment]

    def to_message_dict(self) -> dict[str, Any]:
        """The message as plain data (the field names of ``nav_msgs/OccupancyGrid``), JSON-safe."""
        qx, qy, qz, qw = self.origin_quaternion()
        return {
            "header": {"frame_id": self.frame_id},
            "info": {
                "resolution": self.resolution,
                "width": self.width,
                "height": self.height,
                "origin": {
                    "position": {"x": self.origin[0], "y": self.origin[1], "z": 0.0},
                    "orientation": {"x": qx, "y": qy, "z": qz, "w": qw},
                },
            },
            "data": self.data.tolist(),
        }

    @classmethod
    def from_message(cls, message: Any) -> OccupancyGrid:
        """Read a ``nav_msgs/OccupancyGrid`` (an rclpy message, or the dict of :meth:`to_message_dict`)."""
        info = _get(message, "info")
        header = _get(message, "header", None)
        frame_id = _get(header, "frame_id", "map") if header is not None else "map"
        return cls(
            data=np.asarray(_get(message, "data"), dtype=np.int64),
            width=_get(info, "width"),
            height=_get(info, "height"),
            resolution=_get(info, "resolution"),
            origin=_origin_of(_get(info, "origin")),
            frame_id=str(frame_id or "map"),
        )


def yaw_from_quaternion(x: float, y: float, z: float, w: float, *, check_flat: bool = True) -> float:
    """Yaw (rotation about z, radians) of a quaternion, as ``tf2::getYaw``.

    Raises :class:`~ursim_core.errors.MapError` for a zero quaternion and, with ``check_flat``,
    for one that tilts the map (roll or pitch above 1e-3 rad): a 2-D map must lie flat.

    Examples
    --------
    >>> round(yaw_from_quaternion(*quaternion_from_yaw(1.2)), 12)
    1.2
    """
    values = np.array([x, y, z, w], dtype=float)
    norm = float(np.linalg.norm(values))
    if not math.isfinite(norm) or norm == 0.0:
        raise MapError(f"the origin orientation is not a rotation: quaternion {tuple(values)}", field="origin")
    x, y, z, w = values / norm
    if check_flat:
        roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
        if abs(roll) > _MAX_TILT or abs(pitch) > _MAX_TILT:
            raise MapError(
                f"the origin orientation tilts the map (roll {roll:.4f}, pitch {pitch:.4f} rad): "
                "a 2-D occupancy grid must lie in the x-y plane",
                field="origin",
            )
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quaternion_from_yaw(yaw: float) -> tuple[float, float, float, float]:
    """The (x, y, z, w) quaternion of a rotation by ``yaw`` about z (nav2's ``orientationAroundZAxis``).

    >>> quaternion_from_yaw(0.0)
    (0.0, 0.0, 0.0, 1.0)
    """
    half = float(yaw) / 2.0
    return (0.0, 0.0, math.sin(half), math.cos(half))


def map_from_occupancy_grid(
    data: Any,
    width: int,
    height: int,
    resolution: float,
    origin_pose: Any = (0.0, 0.0, 0.0),
    *,
    path: str | Path | None = None,
) -> Map:
    """Make a :class:`~ursim_core.io.maps.Map` from OccupancyGrid fields.

    Parameters
    ----------
    data : sequence of int or 2-D array
        ``width * height`` cells, row-major, row 0 at the origin (bottom); or an array of shape
        ``(height, width)``, e.g. ``np.reshape(message.data, (height, width))``.
    width, height : int
    resolution : float
        Metres per cell.
    origin_pose : pose
        (x, y, yaw); or (x, y, z, qx, qy, qz, qw); or a mapping / object with ``position``
        (x, y, z) and ``orientation`` (x, y, z, w), e.g. an rclpy ``geometry_msgs/Pose``.
    path : str or Path, optional
        Recorded as ``Map.path``.

    Returns
    -------
    Map
        ``occupancy`` (int8, rows flipped so row 0 is the top), ``free = occupancy == 0``,
        ``resolution``, ``origin`` (x, y, yaw) and a display ``image`` (free 254, occupied 0,
        unknown 205, intermediate values scaled between, as nav2's map_saver draws them).

    Raises
    ------
    MapError
        Wrong number of cells, a 2-D ``data`` not of shape ``(height, width)``, values outside
        int8, a bad origin, or no free cell.

    Examples
    --------
    >>> the_map = map_from_occupancy_grid([0, 0, 100, -1], 2, 2, 0.05, (1.0, 2.0, 0.0))
    >>> the_map.occupancy
    array([[100,  -1],
           [  0,   0]], dtype=int8)
    >>> the_map.free.sum(), the_map.origin
    (np.int64(2), (1.0, 2.0, 0.0))
    """
    cells = np.asarray(data, dtype=np.int64)
    if cells.ndim > 1:
        # ravel() would take a (width, height) array, or any other shape of as many cells, and
        # read its rows as the grid's: a garbled map.
        expected = (_positive_int(height, "height"), _positive_int(width, "width"))
        if cells.shape != expected:
            raise MapError(
                f"data is a {cells.ndim}-D array of shape {cells.shape}, but (height, width) is {expected}: "
                "a 2-D data array must be (height, width), row 0 at the origin (width and height swapped?)",
                path=path,
                field="data",
            )
    grid = OccupancyGrid(
        data=cells.ravel(),
        width=width,
        height=height,
        resolution=resolution,
        origin=_origin_of(origin_pose),
    )
    return _map_of_grid(grid, path=path)


def _map_of_grid(grid: OccupancyGrid, *, path: str | Path | None) -> Map:
    occupancy = grid.cells()
    free = occupancy == OCCUPANCY_FREE
    if not free.any():
        raise MapError(
            f"no free cell in the {grid.width}x{grid.height} occupancy grid "
            f"({int(np.count_nonzero(occupancy == OCCUPANCY_OCCUPIED))} occupied, "
            f"{int(np.count_nonzero(occupancy < 0))} unknown)",
            path=path,
        )
    return Map(
        free=free,
        path=None if path is None else Path(path),
        resolution=grid.resolution,
        origin=grid.origin,
        occupancy=occupancy,
        image=_display_image(occupancy),
    )


def occupancy_from_free(free: np.ndarray, *, unknown: np.ndarray | None = None) -> np.ndarray:
    """Occupancy (int8, row 0 at the top) of a free mask: 0 free, 100 not free, -1 where ``unknown``.

    >>> occupancy_from_free(np.array([[True, False]]))
    array([[  0, 100]], dtype=int8)
    """
    occupancy = np.where(np.asarray(free, dtype=bool), OCCUPANCY_FREE, OCCUPANCY_OCCUPIED).astype(np.int8)
    if unknown is not None:
        occupancy[np.asarray(unknown, dtype=bool)] = OCCUPANCY_UNKNOWN
    return occupancy


def occupancy_grid_from_map(
    the_map: Map,
    *,
    resolution: float | None = None,
    origin: Sequence[float] | None = None,
    frame_id: str = "map",
) -> OccupancyGrid:
    """The OccupancyGrid of a map (the inverse of :func:`map_from_occupancy_grid`).

    The map's ``occupancy`` is used when it has one (ROS maps, maps from a grid); otherwise its
    free mask (0 free, 100 elsewhere: a drawn sketch or an image has no unknown space).

    Parameters
    ----------
    the_map : Map
    resolution : float, optional
        Metres per cell; required when the map has none (an image or a sketch).
    origin : (x, y, yaw), optional
        Overrides the map's origin ((0, 0, 0) when it has none).
    frame_id : str, keyword-only

    Raises
    ------
    ParameterError
        No resolution given and the map has none.

    Examples
    --------
    >>> grid = OccupancyGrid(data=[0, 0, 100, -1], width=2, height=2, resolution=0.05, origin=(1.0, 2.0, 0.3))
    >>> occupancy_grid_from_map(map_from_occupancy_grid(grid.data, 2, 2, 0.05, grid.origin)) == grid
    True
    """
    if resolution is None:
        resolution = the_map.resolution
    if resolution is None:
        raise ParameterError(
            "the map has no resolution (metres per pixel): give one to make an occupancy grid",
            path=the_map.path,
            field="resolution",
        )
    if origin is None:
        origin = the_map.origin if the_map.origin is not None else (0.0, 0.0, 0.0)
    occupancy = the_map.occupancy if the_map.occupancy is not None else occupancy_from_free(the_map.free)
    height, width = occupancy.shape
    return OccupancyGrid(
        data=np.ascontiguousarray(occupancy[::-1]).ravel(),
        width=width,
        height=height,
        resolution=resolution,
        origin=tuple(origin),
        frame_id=frame_id,
    )


# ---------------------------------------------------------------------------------------------
# Helpers


def _display_image(occupancy: np.ndarray) -> np.ndarray:
    # The grey map_saver's scale mode would draw, with trinary's unknown grey: free 254 keeps
    # display and free mask consistent with the loader's 'free = grey > 250' for images.
    values = occupancy.astype(np.float64)
    grey = np.floor((100.0 - np.clip(values, 0, 100)) / 100.0 * 255.0 + 0.5)
    grey = np.where(occupancy == OCCUPANCY_FREE, TRINARY_FREE, grey)
    grey = np.where((occupancy < 0) | (occupancy > 100), TRINARY_UNKNOWN, grey)
    return grey.astype(np.uint8)


def _origin_of(pose: Any) -> tuple[float, float, float]:
    """(x, y, yaw) of any supported pose form (see :func:`map_from_occupancy_grid`)."""
    if isinstance(pose, Mapping) or hasattr(pose, "position"):
        position, orientation = _get(pose, "position"), _get(pose, "orientation", None)
        x, y = float(_get(position, "x")), float(_get(position, "y"))
        if orientation is None:
            return (x, y, 0.0)
        quaternion = [float(_get(orientation, key)) for key in ("x", "y", "z", "w")]
        return (x, y, yaw_from_quaternion(*quaternion))
    try:
        values = [float(value) for value in pose]
    except (TypeError, ValueError):
        raise MapError(f"origin must be (x, y, yaw), (x, y, z, qx, qy, qz, qw) or a Pose, got {pose!r}") from None
    if len(values) == 3:
        return (values[0], values[1], values[2])
    if len(values) == 7:
        return (values[0], values[1], yaw_from_quaternion(*values[3:]))
    raise MapError(f"origin must have 3 (x, y, yaw) or 7 (x, y, z, qx, qy, qz, qw) numbers, got {len(values)}")


_MISSING = object()


def _get(container: Any, key: str, default: Any = _MISSING) -> Any:
    if isinstance(container, Mapping):
        if key in container:
            return container[key]
    elif hasattr(container, key):
        return getattr(container, key)
    if default is _MISSING:
        raise MapError(f"occupancy grid message without '{key}'", field=key)
    return default


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _positive_int(value: Any, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < 1:
        raise MapError(f"{name} must be a positive integer, got {value!r}", field=name)
    return int(value)


def _positive_float(value: Any, name: str) -> float:
    if not _is_real(value) or value <= 0:
        raise MapError(f"{name} must be a positive number (metres per cell), got {value!r}", field=name)
    return float(value)
