"""Turned and mirrored copies of a sketch, with its ground-truth points moved by the same transform.

``ursim evaluate --augment dihedral`` scores every sketch in the 8 orientations of the square
(4 rotations by 90 degrees, each with and without a mirror); ``--augment angles=15,30,...`` turns
it by any angles. Each orientation is scored as its own run.

Conventions (pixel coordinates are ``(row, col)``):

- An :class:`Orientation` mirrors first (``col -> cols - 1 - col``, a left-right flip), then turns
  by ``angle`` degrees counter-clockwise as seen on the screen, about the image centre.
- The canvas grows to hold the whole turned image; pixels that were outside the original image
  are filled with ``fill`` (obstacle: black, not free).
- Images are resampled by nearest neighbour with the inverse transform, so every output pixel is
  a copy of one input pixel; multiples of 90 degrees are exact (a permutation of the pixels).
- A point is moved to the output pixel that is a copy of it (the nearest such pixel to its exact
  image); a pixel that no output pixel copies (possible at odd angles, where nearest-neighbour
  resampling drops some pixels) goes to the pixel nearest its exact image.

Examples
--------
>>> import numpy as np
>>> image = np.arange(6).reshape(2, 3)
>>> turned = transform_image(image, Orientation(90))
>>> turned.tolist()
[[2, 5], [1, 4], [0, 3]]
>>> transform_points([(0, 2)], image.shape, Orientation(90))
[(0, 0)]
>>> int(turned[0, 0]) == int(image[0, 2])
True
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ursim_core.errors import ParameterError

__all__ = [
    "Orientation",
    "UPRIGHT",
    "DIHEDRAL",
    "parse_augment",
    "transformed_shape",
    "transform_image",
    "transform_points",
    "transform_map",
    "transform_correspondences",
]


@dataclass(frozen=True)
class Orientation:
    """A turn by ``angle`` degrees counter-clockwise, after a left-right mirror when ``mirrored``.

    Examples
    --------
    >>> Orientation(90).name, Orientation(0, mirrored=True).name, Orientation(22.5).name
    ('rot90', 'mirror-rot0', 'rot22.5')
    """

    angle: float = 0.0
    mirrored: bool = False

    def __post_init__(self) -> None:
        if not math.isfinite(self.angle):
            raise ParameterError(f"an angle must be a finite number, got {self.angle!r}", field="augment")
        object.__setattr__(self, "angle", float(self.angle) % 360.0)

    @property
    def name(self) -> str:
        """Label of the orientation in tables and the CSV ``augment`` column."""
        angle = format(round(self.angle, 6), "g")
        return ("mirror-" if self.mirrored else "") + f"rot{angle}"

    @property
    def is_identity(self) -> bool:
        return self.angle == 0.0 and not self.mirrored


UPRIGHT = Orientation(0.0)
#: The 8 orientations of the square: 4 turns, then the same 4 mirrored.
DIHEDRAL: tuple[Orientation, ...] = tuple(
    Orientation(angle, mirrored=mirrored) for mirrored in (False, True) for angle in (0, 90, 180, 270)
)


def parse_augment(text: str) -> tuple[Orientation, ...]:
    """Orientations of an ``--augment`` value: ``dihedral`` or ``angles=A,B,...`` (degrees).

    The upright orientation is always included (first), so every run has its reference.

    Examples
    --------
    >>> [o.name for o in parse_augment("angles=15,30")]
    ['rot0', 'rot15', 'rot30']
    >>> len(parse_augment("dihedral"))
    8
    >>> parse_augment("sideways")
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: field 'augment': expected 'dihedral' or 'angles=A,B,...' (degrees), got 'sideways'
    """
    text = text.strip()
    if text.lower() == "dihedral":
        return DIHEDRAL
    if text.lower().startswith("angles="):
        values = []
        for item in text.split("=", 1)[1].split(","):
            if not item.strip():
                continue
            try:
                values.append(float(item))
            except ValueError:
                raise ParameterError(f"'{item.strip()}' is not an angle in degrees", field="augment") from None
        if not values:
            raise ParameterError("angles= needs at least one angle in degrees", field="augment")
        orientations = [UPRIGHT, *(Orientation(value) for value in values)]
        return tuple(dict.fromkeys(orientations))
    raise ParameterError(f"expected 'dihedral' or 'angles=A,B,...' (degrees), got '{text}'", field="augment")


def _cos_sin(angle: float) -> tuple[float, float]:
    # Exact values at multiples of 90 degrees, so those turns map pixels onto pixels exactly.
    quarter = angle / 90.0
    if quarter == round(quarter):
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[int(round(quarter)) % 4]
    radians = math.radians(angle)
    return math.cos(radians), math.sin(radians)


def transformed_shape(shape: Sequence[int], orientation: Orientation) -> tuple[int, int]:
    """``(rows, cols)`` of the canvas that holds the turned image.

    Examples
    --------
    >>> transformed_shape((100, 200), Orientation(90)), transformed_shape((100, 100), Orientation(45))
    ((200, 100), (142, 142))
    """
    rows, cols = int(shape[0]), int(shape[1])
    cos, sin = _cos_sin(orientation.angle)
    # A small tolerance keeps float noise from adding a row or column.
    new_cols = math.ceil(abs(cos) * cols + abs(sin) * rows - 1e-9)
    new_rows = math.ceil(abs(sin) * cols + abs(cos) * rows - 1e-9)
    return max(new_rows, 1), max(new_cols, 1)


def _forward(shape: Sequence[int], orientation: Orientation) -> tuple[np.ndarray, tuple[int, int]]:
    """3x3 matrix taking input (col, row, 1) to output (col, row, 1) coordinates, and the output shape."""
    rows, cols = int(shape[0]), int(shape[1])
    new_rows, new_cols = transformed_shape(shape, orientation)
    cos, sin = _cos_sin(orientation.angle)
    mirror = (
        np.array([[-1.0, 0.0, cols - 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]) if orientation.mirrored else np.eye(3)
    )
    centre_in = np.array([[1.0, 0.0, -(cols - 1) / 2], [0.0, 1.0, -(rows - 1) / 2], [0.0, 0.0, 1.0]])
    # Counter-clockwise on screen, where rows grow downwards.
    turn = np.array([[cos, sin, 0.0], [-sin, cos, 0.0], [0.0, 0.0, 1.0]])
    centre_out = np.array([[1.0, 0.0, (new_cols - 1) / 2], [0.0, 1.0, (new_rows - 1) / 2], [0.0, 0.0, 1.0]])
    return centre_out @ turn @ centre_in @ mirror, (new_rows, new_cols)


def _source_indices(shape: Sequence[int], orientation: Orientation):
    """For every output pixel, the input (row, col) it copies, and whether it lies inside the input."""
    forward, (new_rows, new_cols) = _forward(shape, orientation)
    inverse = np.linalg.inv(forward)
    out_rows, out_cols = np.mgrid[0:new_rows, 0:new_cols]
    src_cols = inverse[0, 0] * out_cols + inverse[0, 1] * out_rows + inverse[0, 2]
    src_rows = inverse[1, 0] * out_cols + inverse[1, 1] * out_rows + inverse[1, 2]
    src_rows = np.rint(src_rows).astype(np.int64)
    src_cols = np.rint(src_cols).astype(np.int64)
    inside = (src_rows >= 0) & (src_rows < shape[0]) & (src_cols >= 0) & (src_cols < shape[1])
    return src_rows, src_cols, inside


def transform_image(image: np.ndarray, orientation: Orientation, *, fill=0) -> np.ndarray:
    """The image turned (and mirrored) on a canvas that holds it; new pixels are ``fill``.

    Works on any array whose first two axes are rows and columns (grey, RGB, bool masks, labels).

    Examples
    --------
    >>> import numpy as np
    >>> transform_image(np.array([[1, 2]]), Orientation(0, mirrored=True)).tolist()
    [[2, 1]]
    >>> transform_image(np.ones((2, 3), bool), Orientation(90), fill=False).shape
    (3, 2)
    """
    image = np.asarray(image)
    if orientation.is_identity:
        return image.copy()
    src_rows, src_cols, inside = _source_indices(image.shape[:2], orientation)
    result = np.empty(src_rows.shape + image.shape[2:], dtype=image.dtype)
    result[...] = fill
    result[inside] = image[src_rows[inside], src_cols[inside]]
    return result


def transform_points(
    points: Iterable[Sequence[int]], shape: Sequence[int], orientation: Orientation
) -> list[tuple[int, int]]:
    """``(row, col)`` points of an image of ``shape`` moved by the transform of :func:`transform_image`.

    Each point goes to the output pixel that copies its input pixel, the nearest to its exact
    image when several do; to the pixel nearest its exact image when none does.

    Examples
    --------
    >>> transform_points([(0, 0), (1, 2)], (2, 3), Orientation(180))
    [(1, 2), (0, 0)]
    """
    points = [(int(row), int(col)) for row, col in points]
    if orientation.is_identity or not points:
        return points
    forward, (new_rows, new_cols) = _forward(shape, orientation)
    inverse = np.linalg.inv(forward)
    moved = []
    for row, col in points:
        exact_col, exact_row, _ = forward @ np.array([col, row, 1.0])
        best = None
        base_row, base_col = math.floor(exact_row), math.floor(exact_col)
        # The output pixels that copy (row, col) lie within one pixel of its exact image.
        for out_row in range(base_row - 1, base_row + 3):
            for out_col in range(base_col - 1, base_col + 3):
                if not (0 <= out_row < new_rows and 0 <= out_col < new_cols):
                    continue
                src_col, src_row, _ = inverse @ np.array([out_col, out_row, 1.0])
                if int(np.rint(src_row)) == row and int(np.rint(src_col)) == col:
                    distance = (out_row - exact_row) ** 2 + (out_col - exact_col) ** 2
                    if best is None or distance < best[0]:
                        best = (distance, out_row, out_col)
        if best is None:
            nearest_row = min(max(int(np.rint(exact_row)), 0), new_rows - 1)
            nearest_col = min(max(int(np.rint(exact_col)), 0), new_cols - 1)
            moved.append((nearest_row, nearest_col))
        else:
            moved.append((best[1], best[2]))
    return moved


def transform_map(the_map, orientation: Orientation):
    """A :class:`~ursim_core.io.maps.Map` turned and mirrored: free space, image and occupancy.

    New pixels are obstacle (not free, black, occupied). The path and SHA-256 still name the
    original file; ``resolution`` and ``origin`` are dropped, as the turned map has no world pose.
    """
    if orientation.is_identity:
        return the_map
    changes = {"free": transform_image(the_map.free, orientation, fill=False), "origin": None, "resolution": None}
    if the_map.image is not None:
        changes["image"] = transform_image(the_map.image, orientation, fill=0)
    if the_map.occupancy is not None:
        changes["occupancy"] = transform_image(the_map.occupancy, orientation, fill=100)
    return dataclasses.replace(the_map, **changes)


def transform_correspondences(corr, shape: Sequence[int], orientation: Orientation):
    """Correspondences whose sketch points are moved as the sketch image of ``shape`` is.

    The metric side is unchanged; region ids are cleared on the sketch side (they belong to the
    old image) and must be assigned again on the turned sketch's segmentation.
    """
    if orientation.is_identity:
        return corr
    cliques = tuple(
        dataclasses.replace(
            clique, sketch_points=tuple(transform_points(clique.sketch_points, shape, orientation)), sketch_regions=()
        )
        for clique in corr.cliques
    )
    return dataclasses.replace(corr, cliques=cliques)
