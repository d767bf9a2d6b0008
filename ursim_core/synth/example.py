"""A generated plan and its sketch from one seed (:func:`make_pair`), and the bundled example pair."""

from __future__ import annotations

import hashlib
from pathlib import Path

import cv2
import numpy as np

from ursim_core.errors import ParameterError
from ursim_core.synth.drawing import Sketch, sketchify
from ursim_core.synth.floor_plans import FloorPlan, generate_floor_plan
from ursim_core.synth.ground_truth import ground_truth_correspondences

__all__ = ["make_pair", "save_example"]


def make_pair(
    *,
    seed: int = 0,
    shape: tuple[int, int] = (400, 512),
    n_rooms: int | None = None,
    corridor_width: int = 30,
    wall_thickness: int = 4,
    door_width: int = 10,
    **sketch_options,
) -> tuple[FloorPlan, Sketch]:
    """A plan and its sketch from one seed.

    Parameters
    ----------
    seed, shape, n_rooms, corridor_width, wall_thickness, door_width : keyword-only
        Passed to :func:`generate_floor_plan` (``seed`` to :func:`sketchify` as well).
    **sketch_options
        Passed to :func:`sketchify`.

    Examples
    --------
    >>> plan, sketch = make_pair(seed=4)
    >>> sketch.free.shape[0] > plan.free.shape[0]
    True
    """
    plan = generate_floor_plan(
        shape=shape,
        n_rooms=n_rooms,
        seed=seed,
        corridor_width=corridor_width,
        wall_thickness=wall_thickness,
        door_width=door_width,
    )
    return plan, sketchify(plan, seed=seed, **sketch_options)


def _png_bytes(free: np.ndarray) -> bytes:
    ok, encoded = cv2.imencode(".png", np.where(free, 255, 0).astype(np.uint8), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    if not ok:
        raise ParameterError("could not encode the map as PNG", field="free")
    return encoded.tobytes()


def save_example(plan: FloorPlan, sketch: Sketch, folder: str | Path, *, now: str | None = None) -> None:
    """Write ``metric.png``, ``sketch.png`` (8-bit grey, 255 free, 0 wall) and ``ground_truth.json``.

    The JSON file is in the project's correspondence format
    (:func:`ursim_core.correspondences.save_correspondences`), with the maps' sizes and
    SHA-256 and one clique per place present in both maps.

    Parameters
    ----------
    plan, sketch
        What to write.
    folder : str or Path
        Created if missing; the three files in it are replaced.
    now : str, optional, keyword-only
        Timestamp to record (``YYYY-MM-DDTHH:MM:SSZ``) so the output is byte-for-byte
        reproducible; the current time by default.

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> save_example(*make_pair(seed=1), folder, now="2024-01-01T00:00:00Z")
    >>> sorted(p.name for p in folder.iterdir())
    ['ground_truth.json', 'metric.png', 'sketch.png']
    """
    import dataclasses

    from ursim_core.correspondences import MapRef, save_correspondences
    from ursim_core.io.atomic import atomic_write_bytes

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    refs = {}
    for side, free in (("metric", plan.free), ("sketch", sketch.free)):
        data = _png_bytes(free)
        path = folder / f"{side}.png"
        atomic_write_bytes(path, data)
        refs[side] = MapRef(path=path.resolve(), sha256=hashlib.sha256(data).hexdigest(), size=tuple(free.shape))
    corr = dataclasses.replace(ground_truth_correspondences(plan, sketch), sketch=refs["sketch"], metric=refs["metric"])
    save_correspondences(corr, folder / "ground_truth.json", now=now)
