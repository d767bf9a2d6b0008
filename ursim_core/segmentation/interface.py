"""Segmentation of a map into regions, behind one small interface.

A segmenter is any callable ``segmenter(free: ndarray[bool], **params) -> ndarray[int32]``
returning a label image (0 = no region, regions 1..N). :func:`segment` wraps it into a
:class:`Segmentation` with its regions (:func:`ursim_core.segmentation.regions.region_table`),
and their adjacency graph (:func:`ursim_core.segmentation.graph.region_graph`) when asked for.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ursim_core.cpus import usable_cpus

if TYPE_CHECKING:  # networkx loads with the region graph, not with this module
    import networkx as nx

    from ursim_core.segmentation.regions import RegionTable

__all__ = [
    "Segmentation",
    "SEGMENTERS",
    "DEFAULT_SEGMENTERS",
    "segment",
    "segment_canonical",
    "why_no_region",
    "resolve_params",
]


_GRAPH_LOCK = threading.Lock()


class Segmentation:
    """A segmented map.

    Immutable (attributes cannot be set); equal only to itself. Give the region graph or the
    region table (:func:`ursim_core.segmentation.regions.region_table`): the other is made
    from it on first use, so that code reading only regions never imports networkx.

    Attributes
    ----------
    labels : ndarray of int32, shape (rows, cols)
        0 = no region; regions are numbered 1..N consecutively.
    graph : networkx.Graph
        Region adjacency graph; nodes are region ids with the attributes of
        :func:`ursim_core.segmentation.graph.region_graph`.
    regions : RegionTable
        The same regions and boundaries as plain dicts.
    method : str
        'maoris' or 'label-image' (or another registered segmenter).
    params : dict
        Parameters used (JSON-serialisable).
    source : Path or None
        Label image path when loaded from a file.
    resampled : tuple of Segmentation
        Other segmentations of the same map, for a sketch that :func:`segment_canonical`
        resamples onto its wall axes (``resampled=True``): turned back by other angles, and not
        turned back. MAORIS's regions change with the resampling, so the matcher votes over the
        answers of all of them (:mod:`ursim_core.matching.resampling`). Empty otherwise, and in
        every segmentation made from edited labels.

    Examples
    --------
    >>> from ursim_core.segmentation.regions import region_table
    >>> labels = np.array([[1, 1, 2], [1, 0, 2]], np.int32)
    >>> seg = Segmentation(labels=labels, regions=region_table(labels))
    >>> seg.n_regions, seg.region_at(0, 2), seg.graph.number_of_edges()
    (2, 2, 1)
    """

    __slots__ = ("_graph", "_regions", "_wall_angle", "labels", "method", "params", "resampled", "source")

    def __init__(
        self,
        labels: np.ndarray,
        graph: nx.Graph | None = None,
        method: str = "maoris",
        params: dict[str, Any] | None = None,
        source: Path | None = None,
        *,
        regions: RegionTable | None = None,
        resampled: tuple[Segmentation, ...] = (),
    ) -> None:
        if graph is None and regions is None:
            raise TypeError("Segmentation needs the region graph or the region table of its labels")
        for name, value in (
            ("labels", labels), ("method", method), ("params", {} if params is None else params), ("source", source),
            ("_graph", graph), ("_regions", regions), ("resampled", tuple(resampled)), ("_wall_angle", None),
        ):  # fmt: skip
            object.__setattr__(self, name, value)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"Segmentation is immutable: cannot set {name!r}")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"Segmentation is immutable: cannot delete {name!r}")

    def __reduce__(self):
        return (
            _rebuilt,
            (self.labels, self._graph, self.method, self.params, self.source, self._regions, self.resampled),
        )

    def __repr__(self) -> str:
        return f"Segmentation(method={self.method!r}, n_regions={self.n_regions}, shape={tuple(self.labels.shape)})"

    def with_resampled(self, resampled: tuple[Segmentation, ...]) -> Segmentation:
        """The same segmentation (labels, regions, graph shared) with ``resampled`` as its other
        segmentations.

        Examples
        --------
        >>> from ursim_core.segmentation.regions import region_table
        >>> labels = np.array([[1, 1, 2]], np.int32)
        >>> seg = Segmentation(labels, regions=region_table(labels))
        >>> other = seg.with_resampled((seg,))
        >>> other.labels is seg.labels, len(other.resampled), seg.resampled
        (True, 1, ())
        """
        other = Segmentation(
            self.labels, self._graph, self.method, self.params, self.source, regions=self._regions, resampled=resampled
        )
        object.__setattr__(other, "_wall_angle", self._wall_angle)  # the same labels
        return other

    @property
    def graph(self) -> nx.Graph:
        if self._graph is None:
            # One graph per segmentation, also when two threads ask at once (the app's views
            # and its jobs): a caller that annotates the graph must see the others' graph.
            with _GRAPH_LOCK:
                if self._graph is None:
                    object.__setattr__(self, "_graph", self._regions.to_graph())
        return self._graph

    @property
    def regions(self) -> RegionTable:
        if self._regions is None:
            from ursim_core.segmentation.regions import RegionTable

            object.__setattr__(self, "_regions", RegionTable.from_graph(self._graph))
        return self._regions

    @property
    def wall_angle(self) -> float:
        """:func:`~ursim_core.segmentation.canonical.wall_angle` of the regions, computed once.

        The matcher reads both maps' wall angles in every orientation search: for a turned
        sketch's vote that is ten searches against the same metric map, and a 4000 x 4000 map
        takes about 20 ms a time.

        Examples
        --------
        >>> from ursim_core.segmentation.regions import region_table
        >>> labels = np.zeros((60, 80), np.int32); labels[10:50, 10:70] = 1
        >>> Segmentation(labels, regions=region_table(labels)).wall_angle
        0.0
        """
        if self._wall_angle is None:
            from ursim_core.segmentation.canonical import wall_angle

            object.__setattr__(self, "_wall_angle", float(wall_angle(self.labels)))
        return self._wall_angle

    @property
    def n_regions(self) -> int:
        return self._graph.number_of_nodes() if self._graph is not None else len(self._regions)

    def region_at(self, row: int, col: int) -> int:
        """Region id under pixel (row, col), 0 when none or outside the image."""
        r, c = int(row), int(col)
        if 0 <= r < self.labels.shape[0] and 0 <= c < self.labels.shape[1]:
            return int(self.labels[r, c])
        return 0


def _rebuilt(labels, graph, method, params, source, regions, resampled=()) -> Segmentation:
    return Segmentation(labels, graph, method, params, source, regions=regions, resampled=resampled)


def _maoris(free: np.ndarray, **params: Any) -> np.ndarray:
    from ursim_core.segmentation.maoris import MaorisParams, maoris_labels

    return maoris_labels(free, MaorisParams.from_dict(params))


def _watershed(free: np.ndarray, **params: Any) -> np.ndarray:
    from ursim_core.segmentation.watershed import watershed_labels

    return watershed_labels(free, **params)


def _learned(free: np.ndarray, **params: Any) -> np.ndarray:
    from ursim_core.segmentation.learned.merging import learned_labels

    return learned_labels(free, **params)


#: Segmenters by name: ``callable(free, **params) -> int32 label image``.
SEGMENTERS: dict[str, Any] = {"maoris": _maoris, "watershed": _watershed, "learned": _learned}
#: The segmenters that label only the box of a mask's free pixels (and a pixel around it), alike
#: wherever that box lies: a canonical segmentation gives them only that part of its canvas
#: (:func:`~ursim_core.segmentation.canonical.canonical_labels`, ``free_box_only``).
SEGMENTERS_OF_THE_FREE_BOX = frozenset({"maoris"})

#: The segmenter and preset to use by kind of map, ``(method, preset)``: the best
#: cross-validated on ``maoris_segmentation`` (:mod:`ursim_core.segmentation.presets_cv`):
#: sketches F1 .838 / .781 (two annotators), robot maps .954 (MAORIS ``default`` .927).
DEFAULT_SEGMENTERS: dict[str, tuple[str, str]] = {"sketch": ("maoris", "sketch"), "robot": ("watershed", "robot")}

#: Preset names of the segmenters other than MAORIS (whose presets are
#: :data:`ursim_core.segmentation.maoris.PRESETS`).
WATERSHED_PRESETS = ("default", "robot")
#: Preset names of learned merging (:mod:`ursim_core.segmentation.learned`): its defaults
#: are made for sketches.
LEARNED_PRESETS = ("default", "sketch")


def method_presets(method: str) -> tuple[str, ...]:
    """Preset names of a segmenter of :data:`SEGMENTERS`, its default first.

    Raises :class:`~ursim_core.errors.ParameterError` for an unknown method.

    Examples
    --------
    >>> method_presets("watershed")
    ('default', 'robot')
    >>> "sketch" in method_presets("maoris")
    True
    """
    from ursim_core.errors import ParameterError

    if method == "maoris":
        from ursim_core.segmentation.maoris import PRESETS

        return tuple(sorted(PRESETS, key=lambda name: name != "default"))
    if method == "watershed":
        return WATERSHED_PRESETS
    if method == "learned":
        return LEARNED_PRESETS
    raise ParameterError(f"unknown segmentation method '{method}' (known: {', '.join(sorted(SEGMENTERS))})")


def resolve_params(
    method: str = "maoris", preset: str | None = "sketch", params: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Full parameter dict of a segmenter: the preset's values updated by ``params``.

    Raises :class:`~ursim_core.errors.ParameterError` for an unknown method, preset or
    parameter name, or an invalid value.

    Examples
    --------
    >>> resolve_params("maoris", "robot", {"doors": 60})["doors"]
    60

    ``canonical`` (True: segment in the map's canonical pose, see
    :mod:`ursim_core.segmentation.canonical`) is a parameter of every method; it is kept in the
    result only when True, so earlier parameter dicts stay as they were. So is
    ``canonical_turn_offset`` (with ``canonical``: degrees added to the turn onto the wall axes,
    or None for no turn; one of the resampled segmentations of :func:`segment_canonical`), kept
    only when given.
    """
    import math

    from ursim_core.errors import ParameterError

    params = dict(params or {})
    canonical = params.pop("canonical", False)
    if canonical not in (True, False):
        raise ParameterError(f"must be true or false, not {canonical!r}", field="canonical")
    turn = {}
    if "canonical_turn_offset" in params:
        offset = params.pop("canonical_turn_offset")
        if offset is not None and (
            isinstance(offset, bool) or not isinstance(offset, (int, float)) or not math.isfinite(offset)
        ):
            raise ParameterError(f"must be a number of degrees or null, not {offset!r}", field="canonical_turn_offset")
        if not canonical:
            raise ParameterError("needs canonical: true", field="canonical_turn_offset")
        turn = {"canonical_turn_offset": None if offset is None else float(offset)}
    resolved = _resolve_method_params(method, preset, params, ParameterError)
    return {**resolved, "canonical": True, **turn} if canonical else resolved


def _resolve_method_params(method, preset, params, ParameterError) -> dict[str, Any]:
    if method not in SEGMENTERS:
        raise ParameterError(f"unknown segmentation method '{method}' (known: {', '.join(sorted(SEGMENTERS))})")
    if method == "watershed":
        from ursim_core.segmentation.watershed import resolve_watershed_params

        # 'sketch' is segment()'s default preset, a MAORIS name: the watershed's defaults.
        if preset not in (None, "sketch", *WATERSHED_PRESETS):
            raise ParameterError(f"unknown preset '{preset}' of the watershed (known: {', '.join(WATERSHED_PRESETS)})")
        return resolve_watershed_params(params or {})
    if method == "learned":
        from ursim_core.segmentation.learned.merging import resolve_learned_params

        if preset not in (None, *LEARNED_PRESETS):
            raise ParameterError(f"unknown preset '{preset}' of learned merging (known: {', '.join(LEARNED_PRESETS)})")
        return resolve_learned_params(params or {})
    if method != "maoris":
        return dict(params or {})
    from ursim_core.segmentation.maoris import PRESETS

    if preset is None:
        preset = "default"
    if preset not in PRESETS:
        raise ParameterError(f"unknown preset '{preset}' (known: {', '.join(sorted(PRESETS))})")
    return PRESETS[preset].with_overrides(**(params or {})).to_dict()


def _free_mask(map_or_free: Any) -> np.ndarray:
    # A grey image's free pixels depend on a threshold (the loader's grey > 250, not "non-zero").
    from ursim_core.errors import ParameterError

    if hasattr(map_or_free, "free"):
        return np.asarray(map_or_free.free, dtype=bool)
    if isinstance(map_or_free, (str, bytes, os.PathLike)):
        raise ParameterError(
            f"got the path {os.fsdecode(map_or_free)!r}: pass a Map (ursim_core.io.load_map(path)) or a bool array",
            field="map_or_free",
        )
    free = np.asarray(map_or_free)
    if free.dtype != bool:
        raise ParameterError(
            f"expected a Map or a bool free-space mask, got an array of {free.dtype}: make a Map of an image "
            "with ursim_core.io.map_from_array(array) (free: grey > 250, as load_map)",
            field="map_or_free",
        )
    return free


def segment(
    map_or_free: Any,
    *,
    method: str = "maoris",
    preset: str | None = "sketch",
    params: dict[str, Any] | None = None,
) -> Segmentation:
    """Segment a map into regions and build its region adjacency graph.

    Parameters
    ----------
    map_or_free : Map or ndarray of bool
        The map (its ``free`` mask is used) or a free-space mask. Make a grey image a Map with
        :func:`ursim_core.io.map_from_array` (free: grey > 250, as ``load_map``).
    method : str
        A key of :data:`SEGMENTERS`.
    preset : str, optional
        Named parameter set of the method (MAORIS: 'sketch', 'robot', 'default', ...;
        watershed: 'default' = 'robot', and 'sketch' gives the same defaults; learned:
        'default' = 'sketch').
    params : dict, optional
        Overrides of single parameters.

    Raises
    ------
    ParameterError
        ``map_or_free`` is a path, or an array not of bool (a uint8 grey image, say).

    Examples
    --------
    >>> free = np.zeros((60, 130), bool)
    >>> free[5:55, 5:60] = True; free[5:55, 70:125] = True; free[27:33, 60:70] = True
    >>> seg = segment(free, preset="default")
    >>> seg.n_regions, seg.graph.number_of_edges()
    (2, 1)
    """
    from ursim_core.segmentation.regions import region_table

    free = _free_mask(map_or_free)
    resolved = resolve_params(method, preset, params)
    settings = {name: value for name, value in resolved.items() if name not in ("canonical", "canonical_turn_offset")}
    if resolved.get("canonical"):
        from ursim_core.segmentation.canonical import canonical_labels

        labels = canonical_labels(
            free,
            lambda pose: SEGMENTERS[method](pose, **settings),
            turn_offset=resolved.get("canonical_turn_offset", 0.0),
            free_box_only=method in SEGMENTERS_OF_THE_FREE_BOX,
        )
    else:
        labels = np.asarray(SEGMENTERS[method](free, **settings), dtype=np.int32)
    return Segmentation(labels=labels, regions=region_table(labels), method=method, params=resolved)


def segment_canonical(
    map_or_free: Any,
    *,
    method: str = "maoris",
    preset: str | None = "sketch",
    params: dict[str, Any] | None = None,
    resampled: bool = False,
) -> Segmentation:
    """:func:`segment` in the map's canonical pose: the same regions however the map is turned.

    For sketches, whose orientation the matcher does not assume; see
    :mod:`ursim_core.segmentation.canonical`. Labels are in the map's own pixel frame;
    ``params`` of the result hold ``"canonical": True`` so that ``segment`` with them gives the
    same segmentation again.

    ``resampled=True``: when the map is resampled onto its wall axes (walls 3 degrees or more off
    the image axes), also segment it turned back by the other angles of
    :data:`~ursim_core.segmentation.canonical.RESAMPLING_OFFSETS` and not turned back, into
    ``Segmentation.resampled`` (five more segmentations), for the matcher to vote over. The
    regions of a resampled sketch depend on the resampling: on the 18 KTH sketches turned by
    15, 30, ..., 345 degrees, the better of two such segmentations per sketch scores 0.76 mean F1
    against 0.69 for the default one (round 30).

    Examples
    --------
    >>> free = np.zeros((100, 170), bool)  # a large and a small room joined by a corridor
    >>> free[10:90, 10:70] = free[30:70, 100:150] = free[45:55, 70:100] = True
    >>> a = segment_canonical(free, preset="default")
    >>> b = segment_canonical(np.rot90(free), preset="default")
    >>> np.array_equal(np.rot90(a.labels), b.labels), a.params["canonical"]
    (True, True)
    """
    params = {**(params or {}), "canonical": True}
    base = segment(map_or_free, method=method, preset=preset, params=params)
    if not resampled:
        return base
    return with_resamplings(base, map_or_free, method=method, params=base.params)


def with_resamplings(
    segmentation: Segmentation, map_or_free: Any, *, method: str, params: dict[str, Any]
) -> Segmentation:
    """``segmentation`` with its other resamplings (``Segmentation.resampled``), as
    ``segment_canonical(..., resampled=True)`` makes them.

    For a canonical segmentation met again without them: its label image reloaded from a file
    (:func:`~ursim_core.segmentation.label_files.load_label_image`, whose method is ``'label-image'``), say, when the method and the
    (resolved) parameters that made it are known. Without them the planar matcher would match
    one segmentation of a sketch that was matched over ten before, and answer otherwise.
    ``segmentation`` itself is returned when it has resamplings already, when ``params`` are not
    canonical (or are one of the resamplings), or when the map is on its wall axes (no
    resampling to vary).

    Examples
    --------
    >>> free = np.zeros((100, 170), bool)
    >>> free[10:90, 10:70] = free[30:70, 100:150] = free[45:55, 70:100] = True
    >>> plain = segment(free, preset="default", params={"canonical": True})
    >>> with_resamplings(plain, free, method="maoris", params=plain.params) is plain  # on its axes
    True
    """
    params = dict(params or {})
    if segmentation.resampled or params.get("canonical") is not True or "canonical_turn_offset" in params:
        return segmentation
    from ursim_core.segmentation.canonical import RESAMPLING_OFFSETS, turned_back

    free = _free_mask(map_or_free)
    if not turned_back(free):
        return segmentation

    # The parameters are resolved already: no preset on top of them.
    def resampling(offset):
        return segment(free, method=method, preset=None, params={**params, "canonical_turn_offset": offset})

    # The first here: it loads (or builds) the kernels once, before any thread could.
    others = [resampling(None)]
    workers = min(len(RESAMPLING_OFFSETS), usable_cpus())
    if workers > 1:
        # The resamplings are independent, and the kernels, OpenCV and the turns release the GIL:
        # on two CPUs the five of rounds 30-32 took 0.27 s instead of 0.44 s for a KTH sketch (round 33). The
        # labels are those made one after the other; map keeps the offsets' order.
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="ursim-resampling") as pool:
            others.extend(pool.map(resampling, RESAMPLING_OFFSETS))
    else:
        others.extend(resampling(offset) for offset in RESAMPLING_OFFSETS)
    return segmentation.with_resampled(tuple(others))


def why_no_region(free: np.ndarray, *, method: str = "maoris") -> str:
    """Why a segmentation of the free-space mask ``free`` by ``method`` found no region, in words
    a user can act on (the CLI's error and the app's status say it).

    Examples
    --------
    >>> free = np.zeros((20, 41), bool); free[2:18, 2:20] = free[2:18, 21:39] = True
    >>> why_no_region(free)[:46]
    '576 free pixel(s) in 2 separate areas with no '
    """
    free = np.asarray(free, bool)
    count = int(free.sum())
    if count == free.size:
        return "every pixel is free: there are no walls to find rooms between"
    if method == "maoris":
        import cv2

        areas = cv2.connectedComponents(free.astype(np.uint8), connectivity=4)[0] - 1
        if areas > 1:
            return (
                f"{count} free pixel(s) in {areas} separate areas with no opening between them: MAORIS drops "
                "every room that touches no other room, as the authors' code does (join the areas by a door, "
                "or segment each on its own)"
            )
    return f"{count} free pixel(s), but no room of the preset's minimum size"
