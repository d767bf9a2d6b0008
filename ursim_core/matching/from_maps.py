"""Two maps matched as ``ursim match`` matches them: each segmented for matching, then matched.

:func:`match` takes two segmentations; how a sketch must be segmented for the matcher is not
its business but matters as much as the matcher itself. The KTH evidence was gathered with the
MAORIS preset of :data:`~ursim_core.matching.config.MATCH_PRESETS` on both maps (``"default"``,
not ``segment``'s own default ``"sketch"``), and a sketch whose orientation the matcher does not
assume is segmented in its canonical pose, with its other resamplings for the planar matcher's
vote. On KTH sketches 00 / 04 / 20 against the model (Malcolm's ground truth), ``segment`` then
``match`` with their defaults scored F1 0.64 / 0.50 / 0.67 and place accuracy 0.93 / 0.75 / 0.75
where this pipeline scores 1.00 / 0.55 / 0.92 and 0.93 / 0.75 / 0.83 (round 60).
:func:`match_maps` is that pipeline for callers of the library; ``ursim match`` and ``ursim goal``
run it too.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any

from ursim_core.errors import ParameterError, SegmentationError
from ursim_core.matching.config import MATCH_PRESETS, MatchConfig

__all__ = [
    "MapsMatch",
    "map_ref",
    "sketch_segmentation_rule",
    "segment_for_matching",
    "segment_pair",
    "match_maps",
]

_SIDES = ("sketch", "metric")


@dataclass(frozen=True)
class MapsMatch:
    """What :func:`match_maps` made: both maps and segmentations, the answer, and the
    configuration the matcher ran with (``scale`` filled in from two georeferenced maps).

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> image = np.zeros((100, 170), np.uint8)  # a large and a small room joined by a corridor
    >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
    >>> found = match_maps(map_from_array(image), map_from_array(image), config=MatchConfig(orientation="upright"))
    >>> found.sketch_seg.n_regions, sorted(found.result.pairs), found.config.orientation
    (3, [(1, 1), (2, 2), (3, 3)], 'upright')
    """

    sketch_map: Any = field(repr=False)
    metric_map: Any = field(repr=False)
    sketch_seg: Any
    metric_seg: Any
    result: Any
    config: MatchConfig = field(repr=False)

    def correspondences(self, *, sketch_labels_path=None, metric_labels_path=None, reviewed=()):
        """The answer as a :class:`~ursim_core.correspondences.Correspondences`, as ``ursim
        match`` writes it: one automatic clique per pair at each region's interior point, each
        map named with its digest and segmentation, and the matcher's record under ``matcher``.

        ``sketch_labels_path`` / ``metric_labels_path``: where the segmentations' label images
        are (or will be) saved (:func:`~ursim_core.segmentation.save_label_image`), for the file
        to name them. ``reviewed``: cliques a person linked, accepted or rejected (on these
        segmentations' regions), kept first; the answer adds its pairs beside them
        (:func:`~ursim_core.matching.constraints.pairs_beside_review`), numbered after them.

        Examples
        --------
        >>> import numpy as np
        >>> from ursim_core.io import map_from_array
        >>> image = np.zeros((100, 170), np.uint8)
        >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
        >>> corr = match_maps(map_from_array(image), map_from_array(image)).correspondences()
        >>> len(corr.cliques), corr.cliques[0].source, sorted(corr.extra)
        (3, 'auto', ['matcher'])
        """
        from ursim_core.correspondences import Correspondences, from_pairs
        from ursim_core.matching.constraints import pairs_beside_review
        from ursim_core.matching.results import match_record

        sketch_graph, metric_graph = self.sketch_seg.graph, self.metric_seg.graph
        reviewed = tuple(reviewed)
        answer = from_pairs(
            pairs_beside_review(self.result.pairs, reviewed),
            sketch_points_of=lambda region: sketch_graph.nodes[region]["interior"],
            metric_points_of=lambda region: metric_graph.nodes[region]["interior"],
            source="auto",
            first_id=max((clique.id for clique in reviewed), default=0) + 1,
        )
        return Correspondences(
            sketch=map_ref(self.sketch_map, self.sketch_seg, labels_path=sketch_labels_path),
            metric=map_ref(self.metric_map, self.metric_seg, labels_path=metric_labels_path),
            cliques=(*reviewed, *answer),
            extra={"matcher": match_record(self.config, self.result)},
        )


def map_ref(the_map: Any, segmentation: Any, *, labels_path=None):
    """The :class:`~ursim_core.correspondences.MapRef` of a map and its segmentation: the map's
    file (absolute), digest and size, the segmenter and its parameters, the label image's path.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> from ursim_core.segmentation import segment
    >>> room = map_from_array(np.ones((40, 60), bool), path="room.png")
    >>> ref = map_ref(room, segment(room, preset="default"), labels_path="room.labels.png")
    >>> ref.path.is_absolute(), ref.size, ref.segmentation_method, ref.labels_path.name
    (True, (40, 60), 'maoris', 'room.labels.png')
    """
    from pathlib import Path

    from ursim_core.correspondences import MapRef

    path = getattr(the_map, "path", None)
    return MapRef(
        path=Path(path).resolve() if path else None,
        sha256=getattr(the_map, "sha256", None),
        size=tuple(the_map.shape),
        segmentation_method=segmentation.method,
        segmentation_params=dict(segmentation.params),
        labels_path=Path(labels_path).resolve() if labels_path is not None else None,
        extra={},
    )


def sketch_segmentation_rule(config: MatchConfig, *, constrained: bool = False) -> tuple[bool, bool]:
    """``(canonical, resampled)``: how the sketch is segmented for ``config``.

    In its canonical pose unless the matcher is told it is upright; in its other resamplings
    too when, turned onto its wall axes, the planar matcher votes over them (not when the match
    is ``constrained`` by fixed pairs, whose region ids belong to one segmentation).

    Examples
    --------
    >>> sketch_segmentation_rule(MatchConfig())
    (True, True)
    >>> sketch_segmentation_rule(MatchConfig(orientation="upright"))
    (False, False)
    >>> sketch_segmentation_rule(MatchConfig(scale=1.0))  # the overlay matcher does not vote
    (True, False)
    """
    canonical = config.orientation != "upright"
    resampled = canonical and config.resampling_vote and config.resolved().matcher == "planar" and not constrained
    return canonical, resampled


def segment_for_matching(
    the_map: Any,
    *,
    side: str,
    config: MatchConfig = MatchConfig(),
    preset: str | None = None,
    params: dict[str, Any] | None = None,
    constrained: bool = False,
) -> Any:
    """Segment ``the_map`` (a :class:`~ursim_core.io.Map`) as the matcher expects its ``side``.

    Parameters
    ----------
    the_map : Map
        From :func:`~ursim_core.io.load_map` or :func:`~ursim_core.io.map_from_array`.
    side : {'sketch', 'metric'}
        The sketch follows :func:`sketch_segmentation_rule`; the metric map is segmented as it is.
    config : MatchConfig, optional
        The configuration the maps will be matched with (pass it after
        :meth:`~MatchConfig.with_resolutions` when both maps are georeferenced).
    preset : str, optional
        MAORIS preset; default ``MATCH_PRESETS[side]``.
    params : dict, optional
        MAORIS parameters over the preset's.
    constrained : bool, optional
        Whether the match will be given fixed pairs (``constraints``).

    Returns
    -------
    Segmentation

    Raises
    ------
    ParameterError
        Unknown side, preset or parameter.
    SegmentationError
        No region was found, naming the map's file and why.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> image = np.zeros((100, 170), np.uint8)  # a large and a small room joined by a corridor
    >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
    >>> segment_for_matching(map_from_array(image), side="sketch").params["canonical"]
    True
    """
    from ursim_core.segmentation import segment, segment_canonical, why_no_region

    if side not in _SIDES:
        raise ParameterError(f"side must be 'sketch' or 'metric', got {side!r}", field="side")
    if not hasattr(the_map, "free"):
        hint = " (load it first: ursim_core.io.load_map(path))" if isinstance(the_map, (str, os.PathLike)) else ""
        raise ParameterError(
            f"must be a Map (ursim_core.io.load_map or map_from_array), got {type(the_map).__name__}{hint}",
            field=f"{side}_map",
        )
    preset = MATCH_PRESETS[side] if preset is None else preset
    canonical, resampled = (
        sketch_segmentation_rule(config, constrained=constrained) if side == "sketch" else (False, False)
    )
    if canonical:
        segmentation = segment_canonical(the_map, preset=preset, params=params, resampled=resampled)
    else:
        segmentation = segment(the_map, preset=preset, params=params)
    if segmentation.n_regions == 0:
        raise SegmentationError(f"0 regions: {why_no_region(the_map.free)}", path=getattr(the_map, "path", None))
    return segmentation


def segment_pair(
    sketch_map: Any,
    metric_map: Any,
    *,
    config: MatchConfig = MatchConfig(),
    sketch_preset: str | None = None,
    metric_preset: str | None = None,
    params: dict[str, Any] | None = None,
    constrained: bool = False,
) -> tuple[Any, Any]:
    """Both maps segmented for matching (:func:`segment_for_matching`), on two threads.

    The MAORIS kernels and OpenCV release the GIL, so two building-sized maps take about the
    time of the larger one (8000 px: about 13 s instead of 23 s). The segmentations are those of
    one after the other; when both fail, the sketch's error is the one raised.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> image = np.zeros((100, 170), np.uint8)  # a large and a small room joined by a corridor
    >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
    >>> sketch_seg, metric_seg = segment_pair(map_from_array(image), map_from_array(image))
    >>> sketch_seg.n_regions, sketch_seg.params["canonical"], "canonical" in metric_seg.params
    (3, True, False)
    """
    from ursim_core.segmentation import segment  # noqa: F401 - imported once here, not by two threads

    def one(the_map, side, preset):
        return segment_for_matching(
            the_map, side=side, config=config, preset=preset, params=params, constrained=constrained
        )

    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="ursim-segment") as pool:
        sketch_job = pool.submit(one, sketch_map, "sketch", sketch_preset)
        metric_job = pool.submit(one, metric_map, "metric", metric_preset)
        return sketch_job.result(), metric_job.result()


def match_maps(
    sketch_map: Any,
    metric_map: Any,
    *,
    config: MatchConfig = MatchConfig(),
    sketch_preset: str | None = None,
    metric_preset: str | None = None,
    params: dict[str, Any] | None = None,
    constraints: Any = None,
    progress=None,
) -> MapsMatch:
    """Match a sketch map to a metric map as ``ursim match`` does.

    Two georeferenced maps (ROS YAML) give the matcher their relative scale
    (:meth:`MatchConfig.with_resolutions`); both maps are segmented for matching
    (:func:`segment_pair`), then matched (:func:`~ursim_core.matching.pipeline.match`).

    Parameters
    ----------
    sketch_map, metric_map : Map
        From :func:`~ursim_core.io.load_map` or :func:`~ursim_core.io.map_from_array`.
    config : MatchConfig, optional
        E.g. ``MatchConfig(orientation="upright")`` for a sketch known to be drawn north up.
    sketch_preset, metric_preset : str, optional
        MAORIS presets; default :data:`~ursim_core.matching.config.MATCH_PRESETS`.
    params : dict, optional
        MAORIS parameters over both presets'.
    constraints : MatchConstraints, optional
        Pairs the answer must contain or avoid.
    progress : callable, optional
        ``progress(fraction, message)`` during the automatic m's sweep.

    Returns
    -------
    MapsMatch
        ``.result.pairs`` are (sketch region, metric region) ids of ``.sketch_seg`` and
        ``.metric_seg``.

    Examples
    --------
    >>> import numpy as np
    >>> from ursim_core.io import map_from_array
    >>> image = np.zeros((100, 170), np.uint8)  # a large and a small room joined by a corridor
    >>> image[10:90, 10:70] = image[30:70, 100:150] = image[45:55, 70:100] = 255
    >>> found = match_maps(map_from_array(image), map_from_array(np.rot90(image).copy()))
    >>> found.sketch_seg.n_regions == found.metric_seg.n_regions == len(found.result.pairs)
    True
    """
    from ursim_core.matching.pipeline import match

    config = config.with_resolutions(getattr(sketch_map, "resolution", None), getattr(metric_map, "resolution", None))
    sketch_seg, metric_seg = segment_pair(
        sketch_map,
        metric_map,
        config=config,
        sketch_preset=sketch_preset,
        metric_preset=metric_preset,
        params=params,
        constrained=constraints is not None,
    )
    result = match(sketch_seg, metric_seg, config=config, progress=progress, constraints=constraints)
    return MapsMatch(sketch_map, metric_map, sketch_seg, metric_seg, result, config)
