"""A turned sketch's other segmentations kept packed in the evaluation until a task needs them.

The local evaluation keeps every segmentation in its main process, and a sketch turned by a free
angle has ten (``Segmentation.resampled``, for the planar matcher's vote). Their label images are
most of the memory: on the 18 KTH sketches at 24 angles the main process held 10.2 GB. A label
image is long runs of one region id along each row, so it is kept as its runs (start and id of
each) and made again, identical, in the worker that matches the sketch.

The first segmentation of such a sketch is packed too (:class:`PackedSegmentation`): the main
process reads its labels only to map the ground truth onto its regions, once per sketch, and its
label image is mostly the empty canvas of the turn: at 24 angles the main process held 4.6 GB of
them once the segmentation had ended (round 58).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Packed",
    "PackedLabels",
    "PackedSegmentation",
    "PackedResamplings",
    "pack_labels",
    "unpack_labels",
    "packed_apart",
    "with_unpacked",
]


@dataclass(frozen=True)
class PackedLabels:
    """A label image as its runs of equal ids in raster order."""

    shape: tuple
    dtype: str
    starts: np.ndarray
    values: np.ndarray

    @property
    def nbytes(self) -> int:
        return int(self.starts.nbytes + self.values.nbytes)


def pack_labels(labels: np.ndarray) -> PackedLabels:
    """The runs of ``labels`` (any shape, any integer type).

    Examples
    --------
    >>> packed = pack_labels(np.array([[0, 0, 1], [1, 1, 2]], np.int32))
    >>> packed.starts.tolist(), packed.values.tolist()
    ([0, 2, 5], [0, 1, 2])
    >>> unpack_labels(packed).tolist()
    [[0, 0, 1], [1, 1, 2]]
    """
    labels = np.asarray(labels)
    flat = labels.ravel()
    if flat.size == 0:
        starts = np.zeros(0, np.int64)
    else:
        starts = np.concatenate(([0], np.flatnonzero(flat[1:] != flat[:-1]) + 1))
    index_type = np.int32 if flat.size < 2**31 else np.int64
    return PackedLabels(tuple(labels.shape), labels.dtype.str, starts.astype(index_type), flat[starts].copy())


def unpack_labels(packed: PackedLabels) -> np.ndarray:
    """The label image :func:`pack_labels` packed, with its shape and type."""
    size = int(np.prod(packed.shape, dtype=np.int64))
    lengths = np.diff(np.append(packed.starts.astype(np.int64), size))
    return np.repeat(packed.values, lengths).astype(np.dtype(packed.dtype), copy=False).reshape(packed.shape)


@dataclass(frozen=True)
class PackedSegmentation:
    """A segmentation with its label image packed, and what the evaluation reads of it.

    ``labels`` is unpacked at each read (a KTH sketch turned by a free angle: milliseconds), and
    nothing keeps it; :meth:`whole` is the :class:`~ursim_core.segmentation.Segmentation`.
    """

    packed_labels: PackedLabels
    regions: Any
    method: str
    params: dict
    source: Any
    #: Its resamplings are packed apart (:class:`PackedResamplings`).
    resampled = ()

    @classmethod
    def of(cls, segmentation: Any) -> PackedSegmentation:
        """``segmentation`` packed, without its resamplings."""
        return cls(
            pack_labels(segmentation.labels),
            segmentation.regions,
            segmentation.method,
            segmentation.params,
            segmentation.source,
        )

    @property
    def labels(self) -> np.ndarray:
        return unpack_labels(self.packed_labels)

    @property
    def n_regions(self) -> int:
        return len(self.regions)

    def whole(self, resampled: tuple = ()) -> Any:
        from ursim_core.segmentation import Segmentation

        return Segmentation(
            self.labels, None, self.method, self.params, self.source, regions=self.regions, resampled=resampled
        )


@dataclass(frozen=True)
class PackedResamplings:
    """``Segmentation.resampled``, each one's labels packed and the rest (regions, method,
    parameters, source) as it was."""

    items: tuple

    @property
    def nbytes(self) -> int:
        return sum(labels.nbytes for labels, *_ in self.items)


def packed_apart(segmentation: Any) -> tuple[Any, PackedResamplings | None]:
    """``segmentation`` without its resamplings, and the resamplings packed (None when it has none).

    A segmentation with resamplings (a turned sketch's) is itself packed
    (:class:`PackedSegmentation`); one without is returned as it is.

    Examples
    --------
    >>> from ursim_core.segmentation import segment_canonical
    >>> from ursim_core.segmentation.canonical import _turned
    >>> from ursim_core.synth import make_pair
    >>> turned, _ = _turned(make_pair(seed=5)[1].free, 25.0)
    >>> sketch = segment_canonical(turned, preset="default", resampled=True)
    >>> alone, packed = packed_apart(sketch)
    >>> alone.resampled, len(packed.items) == len(sketch.resampled), np.array_equal(alone.labels, sketch.labels)
    ((), True, True)
    >>> again = with_unpacked(alone, packed)
    >>> all(np.array_equal(a.labels, b.labels) for a, b in zip(again.resampled, sketch.resampled))
    True
    """
    resampled = getattr(segmentation, "resampled", ())
    if not resampled:
        return segmentation, None
    items = tuple(
        (pack_labels(other.labels), other.regions, other.method, other.params, other.source) for other in resampled
    )
    return PackedSegmentation.of(segmentation), PackedResamplings(items)


def with_unpacked(segmentation: Any, packed: PackedResamplings | None) -> Any:
    """``segmentation`` with the resamplings :func:`packed_apart` packed (itself when None), its
    own labels unpacked when they are packed."""
    from ursim_core.segmentation import Segmentation

    resampled = tuple(
        Segmentation(unpack_labels(labels), None, method, params, source, regions=regions)
        for labels, regions, method, params, source in (packed.items if packed is not None else ())
    )
    if isinstance(segmentation, PackedSegmentation):
        return segmentation.whole(resampled)
    return segmentation if packed is None else segmentation.with_resampled(resampled)


@dataclass(frozen=True)
class Packed:
    """A segmentation kept as :func:`packed_apart` splits it (the evaluation's memory cache)."""

    alone: Any
    resamplings: PackedResamplings | None

    def whole(self) -> Any:
        return with_unpacked(self.alone, self.resamplings)
