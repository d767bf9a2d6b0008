"""Label-image files: a segmentation saved as a 16-bit PNG of region ids (0 = no region).

The region ids are kept as stored, so a correspondence file that names regions of an image
stays valid when the image is loaded again. Errors name the file
(:class:`~ursim_core.errors.SegmentationError`); saves are atomic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ursim_core.segmentation.interface import Segmentation

__all__ = ["read_label_array", "load_label_image", "save_label_image"]


def read_label_array(path: str | Path, *, max_pixels: int | None = None) -> np.ndarray:
    """Read a label image file as an int32 array of the stored ids (0 = no region).

    Accepts 8- or 16-bit single-channel images, and colour images whose channels are equal.
    Raises :class:`~ursim_core.errors.SegmentationError` naming the file otherwise, or when the
    file is not a regular file, is cut, or declares more than ``max_pixels`` pixels in its header
    (checked before decoding, :func:`ursim_core.io.unchanged.read_unchanged`; default
    :data:`~ursim_core.io.maps.DEFAULT_MAX_PIXELS`, the map loader's).
    """
    from ursim_core.errors import SegmentationError
    from ursim_core.io.unchanged import read_unchanged

    path = Path(path)
    if not path.exists():
        raise SegmentationError("label image not found", path=path)
    labels = read_unchanged(path, max_pixels=max_pixels, error=SegmentationError)
    if labels is None:
        raise SegmentationError("not a readable image", path=path)
    if labels.ndim == 3:
        channels = labels[..., :3]
        if not (
            np.array_equal(channels[..., 0], channels[..., 1]) and np.array_equal(channels[..., 0], channels[..., 2])
        ):
            raise SegmentationError("a label image must have one channel (grey, 8 or 16 bit), got colour", path=path)
        labels = channels[..., 0]
    if labels.dtype not in (np.uint8, np.uint16):
        raise SegmentationError(f"a label image must be 8 or 16 bit, got {labels.dtype}", path=path)
    return labels.astype(np.int32)


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
    """Write the label image as a 16-bit PNG (0 = no region), atomically."""
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
