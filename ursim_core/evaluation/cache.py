"""Segmenting the maps of an evaluation once: jobs keyed by file content, memory and disk caches.

A job is one map with its preset and loading options; equal jobs share a result. Cached
segmentations are kept in a caller-owned dict and, optionally, as ``.npz`` label images in a
folder whose file names hash the file's SHA-256, the resolved parameters and the segmenter's
source, so an edited map or a changed segmenter is segmented again.
"""

from __future__ import annotations

import functools
import hashlib
import io
import json
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ursim_core.evaluation.packing import Packed, packed_apart
from ursim_core.evaluation.pool import Progress, completed, pixel_count

__all__ = ["SegmentationJob", "segment_job", "segment_all", "read_cached", "store_segmentation", "check_cache_dir"]


@dataclass(frozen=True)
class SegmentationJob:
    """One map to segment. Equal jobs (same file content, preset, loading and orientation) share
    a result, so a model stored under two names (Halmstad: GT/Malcolm/model_simple.png =
    E5_08.png) and a map used by several experiments are segmented once.

    ``orientation`` (an :class:`~ursim_core.evaluation.augment.Orientation`, None for the map as
    it is) turns and mirrors the loaded map before it is segmented. ``canonical`` segments it with
    :func:`ursim_core.segmentation.canonical.segment_canonical` (sketches, whose orientation is
    unknown to the matcher), else with ``segment``; ``resampled`` (with ``canonical``) also in
    the other resamplings of a map resampled onto its wall axes, for the planar matcher's vote."""

    path: Path = field(compare=False)
    digest: str
    preset: str
    load_key: str
    augment: str = ""
    orientation: Any = field(default=None, compare=False)
    canonical: bool = False
    resampled: bool = False

    @classmethod
    def of(
        cls,
        path: Path,
        preset: str,
        load: dict,
        digests: dict[Path, str],
        orientation: Any = None,
        *,
        canonical: bool = False,
        resampled: bool = False,
    ) -> SegmentationJob:
        path = Path(path)
        if path not in digests:
            try:
                digests[path] = hashlib.sha256(path.read_bytes()).hexdigest()
            except OSError:
                # load_map reports the real problem, naming the file, when the map is loaded.
                digests[path] = f"unreadable:{path.resolve()}"
        if orientation is not None and orientation.is_identity:
            orientation = None
        return cls(
            path=path,
            digest=digests[path],
            preset=preset,
            load_key=json.dumps(load, sort_keys=True),
            augment="" if orientation is None else orientation.name,
            orientation=orientation,
            canonical=canonical,
            resampled=canonical and resampled,
        )

    @property
    def key(self) -> str:
        return (
            f"{self.digest}|{self.preset}|{self.load_key}"
            + (f"|{self.augment}" if self.augment else "")
            + ("|canonical" if self.canonical else "")
            + ("|resampled" if self.resampled else "")
        )

    @property
    def load(self) -> dict:
        return json.loads(self.load_key)


def segment_job(job: SegmentationJob):
    """Load and segment one map (runs in a worker process)."""
    from ursim_core.io.maps import load_map
    from ursim_core.segmentation import segment

    the_map = load_map(job.path, **job.load)
    if job.orientation is not None:
        from ursim_core.evaluation.augment import transform_map

        the_map = transform_map(the_map, job.orientation)
    if job.canonical:
        from ursim_core.segmentation import segment_canonical

        return segment_canonical(the_map, preset=job.preset, resampled=job.resampled)
    return segment(the_map, preset=job.preset)


@functools.lru_cache(maxsize=1)
def _segmenter_code_digest() -> str:
    """Digest of every source file of the segmentation package: a cached result is stale when any changes."""
    import ursim_core.segmentation as package

    digest = hashlib.sha256()
    root = Path(package.__file__).parent
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()


def _disk_cache_path(cache_dir: Path, job: SegmentationJob) -> Path:
    from ursim_core.segmentation import resolve_params

    # The resolved parameters (not only the preset name) and the segmenter's source go in the
    # key, so a changed preset definition or a changed MAORIS implementation invalidates the cache.
    identity = json.dumps(
        {
            "sha256": job.digest,
            "params": resolve_params("maoris", job.preset),
            "load": job.load,
            "version": 1,
            "code": _segmenter_code_digest(),
            # Only augmented jobs carry the key, so the cache files of upright maps keep their names.
            **({"augment": job.augment} if job.augment else {}),
            **({"canonical": True} if job.canonical else {}),
            **({"resampled": True} if job.resampled else {}),
        },
        sort_keys=True,
    )
    return cache_dir / f"{job.path.stem}-{hashlib.sha256(identity.encode()).hexdigest()[:24]}.npz"


#: What a damaged, cut or foreign ``.npz`` raises when opened or read: a cut zip archive
#: (BadZipFile, EOFError), a damaged compressed member (zlib.error), a bad array header or object
#: arrays (ValueError), a forged header's shape (MemoryError), a missing member (KeyError), and
#: members of another form than written (TypeError, OverflowError: a 0-d shape, an infinite one).
_DAMAGED_CACHE = (
    OSError,
    KeyError,
    ValueError,
    TypeError,
    OverflowError,
    EOFError,
    MemoryError,
    zipfile.BadZipFile,
    zlib.error,
)


def _read_disk_cache(path: Path, job: SegmentationJob):
    """The segmentation stored for ``job`` at ``path``, or None when there is no usable one.

    A stored segmentation is used only when it names the map it is for (its SHA-256, as the job)
    and every label image in it is a 2-D array of non-negative integers of that map's shape (as it
    was segmented): anything else is a cache miss, as a missing file is, and is segmented again.
    """
    from ursim_core.segmentation import Segmentation, resolve_params
    from ursim_core.segmentation.regions import region_table

    params = resolve_params("maoris", job.preset, {"canonical": job.canonical})
    try:
        with np.load(path) as stored:
            if str(stored["map_sha256"]) != job.digest:
                return None  # another map's file under this name (copied, or renamed)
            shape = tuple(int(v) for v in stored["map_shape"])
            labels = _stored_labels(stored["labels"], shape)
            # The other resamplings (segment_canonical(..., resampled=True)) and their turns.
            offsets = [float(v) for v in stored["resampled_offsets"]] if "resampled_offsets" in stored else []
            others = [_stored_labels(stored[f"resampled_{index}"], shape) for index in range(len(offsets))]
    except _DAMAGED_CACHE:
        # A missing, damaged or foreign cache file is only a cache miss.
        return None
    if labels is None or any(other is None for other in others):
        return None
    resampled = tuple(
        Segmentation(
            labels=other,
            regions=region_table(other),
            method="maoris",
            params={**params, "canonical_turn_offset": None if np.isnan(offset) else offset},
        )
        for other, offset in zip(others, offsets, strict=True)
    )
    return Segmentation(
        labels=labels, regions=region_table(labels), method="maoris", params=params, resampled=resampled
    )


def _stored_labels(array: np.ndarray, shape: tuple[int, ...]) -> np.ndarray | None:
    """``array`` as int32 labels when it is a label image of ``shape`` (the map's), else None.

    Labels of another shape would be scored against the map's ground truth as if they were its
    own: points off their image dropped, the rest read at the wrong pixels.
    """
    if array.ndim != 2 or array.shape != shape or array.dtype.kind not in "iu":
        return None
    if array.size and (int(array.min()) < 0 or int(array.max()) > np.iinfo(np.int32).max):
        return None
    return array.astype(np.int32)


def _write_disk_cache(path: Path, job: SegmentationJob, segmentation) -> None:
    from ursim_core.io.atomic import atomic_write_bytes

    buffer = io.BytesIO()
    others = {f"resampled_{index}": other.labels for index, other in enumerate(segmentation.resampled)}
    if others:
        offsets = [other.params.get("canonical_turn_offset") for other in segmentation.resampled]
        others["resampled_offsets"] = np.array([np.nan if o is None else o for o in offsets], float)
    # The map's digest and shape: what a read checks the file against (_read_disk_cache).
    np.savez_compressed(
        buffer,
        labels=segmentation.labels,
        map_sha256=np.array(job.digest),
        map_shape=np.array(segmentation.labels.shape, np.int64),
        **others,
    )
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, buffer.getvalue())
    except OSError:
        # A read-only or full cache folder must not fail the evaluation.
        pass


def read_cached(job: SegmentationJob, memory_cache, cache_dir):
    """The job's segmentation from the memory cache, else the disk cache (kept in memory), or None.

    The memory cache may hold it with its resamplings packed (:class:`~.packing.Packed`, what
    :func:`segment_all` keeps when asked to pack): it is returned whole.
    """
    found = _from_memory(job, memory_cache)
    if found is None and cache_dir is not None:
        found = _read_disk_cache(_disk_cache_path(Path(cache_dir), job), job)
        if found is not None and memory_cache is not None:
            memory_cache[job.key] = found
    return found.whole() if isinstance(found, Packed) else found


def _from_memory(job: SegmentationJob, memory_cache):
    return memory_cache.get(job.key) if memory_cache is not None else None


def store_segmentation(job: SegmentationJob, segmentation, memory_cache, cache_dir) -> None:
    """Keep a computed segmentation in the memory cache and the disk cache (when given)."""
    if memory_cache is not None:
        memory_cache[job.key] = segmentation
    if cache_dir is not None:
        _write_disk_cache(_disk_cache_path(Path(cache_dir), job), job, segmentation)


def check_cache_dir(cache_dir: str | Path) -> None:
    """Refuse a cache folder that is a file, or that cannot be made because a parent is a file.

    Writing the cache fails quietly (a read-only or full folder must not fail an evaluation), so
    without this a file named as the folder would only make every run segment everything again.

    Raises
    ------
    ParameterError
        Naming the path.
    """
    from ursim_core.errors import ParameterError

    folder = Path(cache_dir)
    existing = folder
    while not existing.exists() and existing.parent != existing:
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        where = "this is a file" if existing == folder else f"{existing} is a file"
        raise ParameterError(f"the segmentation cache (--cache) must be a folder, but {where}", path=folder)


def split_cached(jobs, reporter: Progress, memory_cache, cache_dir, packed: dict | None = None):
    """The cached segmentations by job key, and the jobs still to run, biggest map first.

    Biggest first so that the workers (local processes or a Dask cluster) finish together.
    ``packed``: see :func:`segment_all`.
    """
    if cache_dir is not None:
        check_cache_dir(cache_dir)
    segmentations: dict[str, Any] = {}
    to_run = []
    for job in jobs:
        found = _from_memory(job, memory_cache)
        if packed is None or not isinstance(found, Packed):
            found = read_cached(job, memory_cache, cache_dir)
        if found is None:
            to_run.append(job)
        else:
            segmentations[job.key] = _kept(job, found, memory_cache, packed)
            reporter.step(f"segment {job.path.name} (cached)")
    to_run.sort(key=lambda job: -pixel_count(job.path))
    return segmentations, to_run


def record_segmentation(
    job, segmentation, segmentations: dict, reporter: Progress, memory_cache, cache_dir, packed: dict | None = None
):
    """Keep a computed segmentation: in the result, in the caches, and say so."""
    store_segmentation(job, segmentation, memory_cache, cache_dir)
    segmentations[job.key] = _kept(job, segmentation, memory_cache, packed)
    turned = f" {job.augment}" if job.augment else ""
    reporter.step(f"segment {job.path.name}{turned}: {segmentation.n_regions} regions")


def _kept(job: SegmentationJob, found, memory_cache, packed: dict | None):
    """What the result keeps of a segmentation (or of a :class:`~.packing.Packed` one): all of it,
    or with ``packed`` its resamplings packed into ``packed[job.key]``, the memory cache holding
    the packed form too (:mod:`ursim_core.evaluation.packing`)."""
    if packed is None:
        return found
    if not isinstance(found, Packed):
        found = Packed(*packed_apart(found))
        if memory_cache is not None:
            memory_cache[job.key] = found
    if found.resamplings is not None:
        packed[job.key] = found.resamplings
    return found.alone


def segment_all(jobs, workers: int, reporter: Progress, memory_cache, cache_dir, *, packed: dict | None = None):
    """Segmentations by job key, from the caches or computed biggest map first.

    ``packed``: a dict that receives, by job key, the resamplings of every segmentation that has
    some, packed (:func:`ursim_core.evaluation.packing.packed_apart`); the segmentations returned
    then have none. The disk cache keeps them whole, the memory cache packed.
    """
    segmentations, to_run = split_cached(jobs, reporter, memory_cache, cache_dir, packed)
    cached = len(jobs) - len(to_run)
    for job, segmentation in completed(segment_job, to_run, workers=workers):
        record_segmentation(job, segmentation, segmentations, reporter, memory_cache, cache_dir, packed)
    return segmentations, cached
