"""Label-image files: a segmentation saved as a 16-bit PNG of region ids (0 = no region).

The region ids are kept as stored, so a correspondence file that names regions of an image
stays valid when the image is loaded again. Errors name the file
(:class:`~ursim_core.errors.SegmentationError`); saves are atomic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ursim_core.io.unchanged import read_label_array
from ursim_core.segmentation.interface import Segmentation

# read_label_array lives in io (the correspondence exporters read label images too); it is
# part of this module's API, where users of segmentations look for it.
__all__ = ["read_label_array", "load_label_image", "save_label_image"]


def load_label_image(
    path: str | Path, *, shape: tuple[int, int] | None = None, max_pixels: int | None = None
) -> Segmentation:
    """Load a label image (8- or 16-bit single-channel PNG, 0 = no region) as a segmentation.

    Region ids are kept as stored, so ids in a correspondence file that references this
    image stay valid.

    Parameters
    ----------
    path : str or Path
        The label image.
    shape : (rows, cols), optional
        Required size (the map's); a mismatch raises :class:`~ursim_core.errors.SegmentationError`.
    max_pixels : int, optional
        Largest image read (:func:`read_label_array`); by default the map loader's default, or
        the pixels of ``shape`` when more (the map was loaded with a higher limit).

    Examples
    --------
    >>> import tempfile
    >>> from ursim_core.segmentation import region_table
    >>> labels = np.array([[0, 7, 7], [3, 3, 0]], np.int32)
    >>> path = Path(tempfile.mkdtemp()) / "rooms.png"
    >>> save_label_image(Segmentation(labels, regions=region_table(labels)), path)
    >>> seg = load_label_image(path, shape=(2, 3))
    >>> seg.labels.tolist(), seg.method, sorted(seg.regions.nodes)  # ids kept as stored
    ([[0, 7, 7], [3, 3, 0]], 'label-image', [3, 7])
    >>> load_label_image(path, shape=(3, 3))
    Traceback (most recent call last):
    ...
    ursim_core.errors.SegmentationError: ...rooms.png: label image is 2x3 (rows x cols) but the map is 3x3
    """

    from ursim_core.errors import SegmentationError
    from ursim_core.segmentation.regions import region_table

    path = Path(path)
    if max_pixels is None and shape is not None:
        from ursim_core.io.maps import DEFAULT_MAX_PIXELS

        max_pixels = max(DEFAULT_MAX_PIXELS, int(shape[0]) * int(shape[1]))
    labels = read_label_array(path, max_pixels=max_pixels)
    if shape is not None and tuple(labels.shape) != tuple(shape):
        raise SegmentationError(
            f"label image is {labels.shape[0]}x{labels.shape[1]} (rows x cols) but the map is {shape[0]}x{shape[1]}",
            path=path,
        )
    return Segmentation(labels=labels, regions=region_table(labels), method="label-image", params={}, source=path)


def save_label_image(segmentation: Segmentation, path: str | Path) -> None:
    """Write the label image as a 16-bit PNG (0 = no region), atomically.

    Examples
    --------
    >>> import tempfile
    >>> from ursim_core.segmentation import region_table
    >>> labels = np.array([[0, 1], [2, 300]], np.int32)
    >>> path = Path(tempfile.mkdtemp()) / "labels.png"
    >>> save_label_image(Segmentation(labels, regions=region_table(labels)), path)
    >>> read_label_array(path).tolist()  # ids above 255 survive: 16 bits
    [[0, 1], [2, 300]]
    """
    import cv2

    from ursim_core.errors import SegmentationError
    from ursim_core.io.atomic import atomic_write_bytes

    labels = segmentation.labels
    if labels.size and int(labels.max()) > 65535:
        raise SegmentationError(f"{int(labels.max())} regions do not fit a 16-bit label image", path=path)
    ok, encoded = cv2.imencode(".png", labels.astype(np.uint16))
    if not ok:
        raise SegmentationError("could not encode the label image", path=path)
    atomic_write_bytes(Path(path), encoded.tobytes())
