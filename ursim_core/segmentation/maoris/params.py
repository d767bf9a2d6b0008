"""MAORIS parameters and the named parameter sets.

``PRESETS`` holds the parameter sets met in the original code and one chosen
by measurement for sketches:

=================  =====  =====  ==========================================
name               t      doors  origin
=================  =====  =====  ==========================================
``default``        0.25   40     GraphZone defaults; GT correspondences
                                 were clicked on these segmentations
``robot``          0.50   40     URSIM driver, robot maps
``ursim-released`` 0.50   40     = robot (the released driver used it for
                                 sketches too, ``is_sketch = false``)
``icra``           0.30   40     MAORIS paper evaluation
``sketch``         0.15   100    chosen by leave-one-map-out cross-validation
                                 on sketches (also quantum 8, ripples 45,
                                 small_after 0; see below)
=================  =====  =====  ==========================================

``sketch`` is the candidate of a grid (threshold 0.15/0.20/0.25 x doors 50/100 x
quantum 5/8 x ripples 40/45 x small_after 0/100) with the best mean F1 over the 18
sketches of ``maoris_segmentation`` and both annotators. Chosen the same way without
each sketch in turn and scored on it (leave-one-map-out,
:func:`ursim_core.segmentation.presets_cv.cross_validate`), it scores F1 .838 / .781
(mean .810; worst sketch .696 / .613) against ``gt_lex`` / ``gt_ezvin``, in-sample .842
/ .785; the annotators agree with each other at .872 (worst .772). The same rule on the
threshold x doors grid below (the earlier ``sketch``, t=0.25 doors 50) gives .795 / .728
cross-validated. Door fusion is off (doors 100): the grid chose it over doors 50.

Earlier measurement (in-sample, the earlier ``sketch`` preset): the 18 sketches of
``maoris_segmentation/sketches/maps`` (free = grey > 250), scored with
:func:`ursim_core.segmentation.scoring.score_segmentation` against both
annotators; mean over sketches of P, R, F1 (``evF1``: the C++ evaluator's
per-predicted-region precision). ``authors`` = their label images
``maoris_output/NN.png`` scored the same way. Reproduce with
``ursim_core.bench.segmentation.bench_quality``::

    preset          gt_lex P/R/F1      gt_ezvin P/R/F1    mean F1  evF1 lex/ezvin
    authors         .693 .901 .777     .599 .911 .713     .745     .895 .883
    t=0.25 doors 40 .665 .893 .759     .572 .909 .696     .727     .883 .878
    t=0.25 doors 50 .712 .891 .788     .608 .904 .719     .753     .891 .883  <- earlier sketch
    t=0.25 doors 60 .720 .889 .792     .615 .904 .725     .758     .890 .884
    t=0.30 doors 40 .640 .898 .743     .551 .914 .681     .712     .883 .877
    t=0.30 doors 60 .691 .896 .777     .591 .909 .708     .742     .890 .883
    t=0.35 doors 40 .630 .904 .739     .541 .917 .672     .705     .884 .877
    t=0.35 doors 60 .668 .900 .763     .572 .912 .694     .729     .887 .881
    t=0.40 doors 40 .592 .912 .713     .512 .923 .652     .682     .880 .874
    t=0.40 doors 60 .617 .910 .729     .533 .921 .668     .699     .882 .878
    t=0.50 doors 40 .541 .923 .675     .470 .932 .615     .645     .877 .870
    t=0.50 doors 60 .549 .922 .681     .478 .931 .621     .651     .877 .870

The earlier ``sketch`` used doors 50 rather than the slightly higher-scoring 60: a square
door passage (as long as it is wide) touches other regions on 52-56 % of its
contour, so doors 60 leaves such passages as regions of their own, which the
matcher then has to place; 50 fuses them and still beats the authors' label
images on both ground truths. Outside the grid, t=0.20 with doors 80 reaches
mean F1 .789 but over-segments (lower precision per predicted region on the
robot maps below).

The 15 robot maps of ``maoris_segmentation/robot_maps`` (free = grey > 250)
against ``gt``, same measure::

    preset          P    R    F1   evF1
    robot (t=0.50)  .811 .955 .857 .948
    default (0.25)  .919 .942 .925 .956
    icra (0.30)     .899 .946 .914 .956
    t=0.25 doors 60 .920 .942 .925 .954
    t=0.40 doors 40 .865 .951 .896 .956
    t=0.20 doors 80 .930 .938 .928 .925

"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ursim_core.errors import ParameterError

__all__ = ["MaorisParams", "PRESETS"]


@dataclass(frozen=True)
class MaorisParams:
    """Parameters of the MAORIS segmentation (GraphZone defaults).

    Attributes
    ----------
    threshold : float
        Watershed relative-difference threshold t in [0, 1); also the
        unbreakable-edge test ``min <= max(va, vb) * (1 - t)``.
    margin : float
        Extra tolerance of the watershed when a close neighbour exists, in [0, 1).
    ripples : float
        Percent of a zone's contour touching a neighbour that makes it a
        ripple of that neighbour, in [0, 100].
    doors : float
        Percent (summed over neighbours) of a region's contour touching other
        regions above which it is a door and is fused, >= 0.
    max_radius : int
        Largest inscribed-disc radius considered, px (1 .. 2**53).
    quantum : int
        Values are rounded up to multiples of this (1..255).
    small_before : int
        Zones smaller than this (px) are fused before ripple merging (0 .. 2**53).
    small_after : int
        Regions smaller than this (px) are fused after door removal (0 .. 2**53).

    Examples
    --------
    >>> MaorisParams().threshold
    0.25
    >>> MaorisParams().with_overrides(doors=60).doors
    60
    """

    threshold: float = 0.25
    margin: float = 0.10
    ripples: float = 40
    doors: float = 40
    max_radius: int = 500
    quantum: int = 5
    small_before: int = 10
    small_after: int = 100

    def __post_init__(self) -> None:
        for name, (kind, low, high, high_open) in _PARAM_RULES.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ParameterError(f"must be a number, got {value!r}", field=name)
            # The range first, compared as given (float() of an integer of 400 digits overflows):
            # a huge integer is "out of range", not "not an integer" (as a float it is not one),
            # and no value past it reaches a kernel's 64-bit argument.
            if (
                (isinstance(value, (float, np.floating)) and not math.isfinite(value))
                or value < low
                or (high is not None and (value >= high if high_open else value > high))
            ):
                bound = "" if high is None else (f" and < {high}" if high_open else f" and <= {high}")
                raise ParameterError(f"must be >= {low}{bound}, got {value!r}", field=name)
            if kind is int and float(value) != int(value):
                raise ParameterError(f"must be an integer, got {value!r}", field=name)
            # Store plain Python numbers so to_dict() is JSON-serialisable.
            object.__setattr__(self, name, int(value) if kind is int else _plain_number(value))

    def to_dict(self) -> dict[str, Any]:
        """Parameters as a JSON-serialisable dict.

        Examples
        --------
        >>> MaorisParams().to_dict()["doors"]
        40
        """
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> MaorisParams:
        """Build parameters from a dict; missing names take the defaults.

        Raises
        ------
        ParameterError
            For an unknown name or an invalid value (the message names it).

        Examples
        --------
        >>> MaorisParams.from_dict({"threshold": 0.5}).threshold
        0.5
        """
        return cls().with_overrides(**dict(values))

    def with_overrides(self, **overrides: Any) -> MaorisParams:
        """Copy with some parameters replaced, validating names and values.

        Examples
        --------
        >>> PRESETS["robot"].with_overrides(margin=0.2).margin
        0.2
        """
        known = {f.name for f in dataclasses.fields(self)}
        for name in overrides:
            if name not in known:
                raise ParameterError(f"unknown MAORIS parameter (known: {', '.join(sorted(known))})", field=str(name))
        return dataclasses.replace(self, **overrides)


def _plain_number(value: Any) -> int | float:
    value = float(value)
    return int(value) if value.is_integer() and abs(value) < 2**53 else value


#: Largest size (px) and radius accepted: far more pixels than any map a computer holds (a larger
#: value fuses every zone, or bounds no disc, just as this one does), and the largest integers a
#: float holds exactly, so a value written 1e20 is not silently rounded. Without a bound, 1e20 went
#: to the kernels' 64-bit arguments as an OverflowError traceback.
_SIZE_MAX = 2**53

# name -> (kind, minimum, maximum or None, maximum excluded)
_PARAM_RULES: dict[str, tuple[type, float, float | None, bool]] = {
    "threshold": (float, 0.0, 1.0, True),
    "margin": (float, 0.0, 1.0, True),
    "ripples": (float, 0.0, 100.0, False),
    "doors": (float, 0.0, None, False),
    "max_radius": (int, 1, _SIZE_MAX, False),
    "quantum": (int, 1, 255, False),
    "small_before": (int, 0, _SIZE_MAX, False),
    "small_after": (int, 0, _SIZE_MAX, False),
}

PRESETS: dict[str, MaorisParams] = {
    "default": MaorisParams(),
    "robot": MaorisParams(threshold=0.50, doors=40),
    "ursim-released": MaorisParams(threshold=0.50, doors=40),
    "icra": MaorisParams(threshold=0.30, doors=40),
    # Chosen by leave-one-map-out cross-validation on the sketches (module docstring).
    "sketch": MaorisParams(threshold=0.15, doors=100, quantum=8, ripples=45, small_after=0),
}
