"""The matcher's options (:class:`MatchConfig`) and the constants every matching module shares.

Every departure of the released C++ code and every extension beyond the paper is a named option,
so each can be measured. :meth:`MatchConfig.paper` is the paper's method as published,
:meth:`MatchConfig.released` turns every released-code option on, and the default
``MatchConfig()`` is the paper's method plus the extensions the evidence supports (position-aware
comparison, signature-aware hypothesis score, automatic m, orientation-free matching).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

from ursim_core.errors import ParameterError

__all__ = [
    "MATCH_PRESETS",
    "M_GRID",
    "MATCHERS",
    "AUTO_RULE_NAMES",
    "DEFAULT_TIMES",
    "SIZE_WEIGHT_FLOOR",
    "VARIANTS",
    "ORIENTATIONS",
    "ELASTIC_RULES",
    "ELASTIC_LAYINGS",
    "ELASTIC_LAYING_RULES",
    "ELASTIC_PARTNERS",
    "PARTIAL_SKETCH",
    "MatchConfig",
]

# The constants the options name live here, not in the modules that use them (descriptors,
# signatures, orientation), which import networkx: ``ursim match`` builds its parser and its
# MatchConfig without it, and imports the matcher while it loads and segments the maps.

#: t = i * 0.2 for i = 0..14, as the paper and the released driver (15 samples, 0 .. 2.8).
DEFAULT_TIMES = tuple(round(0.2 * i, 10) for i in range(15))
#: Added to ``z_size - min(z_size)`` so that no vertex gets weight 0 (see :mod:`.descriptors`).
SIZE_WEIGHT_FLOOR = 0.1
VARIANTS = ("T1", "T2", "T3", "T4", "baseline")
#: The values of ``MatchConfig.elastic`` (see :mod:`ursim_core.matching.elastic`).
ELASTIC_RULES = ("off", "alone", "completed")
#: What each value of ``MatchConfig.elastic_laying`` lays the sketch by (see
#: :mod:`ursim_core.matching.elastic`): the window rule ('off'; 'clear', the best window when it
#: correlates clearly better than the whole box; 'competes', the window and the boxes, whichever
#: lands more) and whether the planar answer's laying competes too.
ELASTIC_LAYING_RULES = {
    "boxes": ("off", False),
    "boxes_or_answer": ("off", True),
    "window": ("clear", False),
    "window_or_answer": ("clear", True),
    "boxes_or_window": ("competes", False),
}
#: The values of ``MatchConfig.elastic_laying``.
ELASTIC_LAYINGS = tuple(ELASTIC_LAYING_RULES)
#: The values of ``MatchConfig.elastic_partners``.
ELASTIC_PARTNERS = ("neighbours", "all")
#: The options for a sketch known to show only part of the metric map (``ursim match --partial``,
#: the app's "Part" box). Round 48, generated pairs: the partial kinds 0.812 -> 0.836 mean F1;
#: round 50 added ``window_start``: 0.835 -> 0.854 and 0.838 -> 0.860 (seeds 0-63 / 64-127). Not
#: the default, since a whole hand-drawn sketch can land better in a window that pairs it worse,
#: and the windows cost (docs/options.md).
PARTIAL_SKETCH = {"elastic_laying": "boxes_or_window", "window_reading_margin": 0.1, "window_start": True}
#: The values of ``MatchConfig.orientation`` other than a number of degrees.
ORIENTATIONS = ("any", "upright")

#: Rules of ``m='auto'`` (implemented in :mod:`ursim_core.matching.auto_m`).
AUTO_RULE_NAMES = ("score", "structure")

#: MAORIS preset used for both maps when matching (the evidence: docs/options.md).
MATCH_PRESETS = {"sketch": "default", "metric": "default"}


#: The released driver's sweep: 0, 0.025, ..., 0.475 (20 values).
M_GRID = tuple(round(0.025 * i, 10) for i in range(20))
MATCHERS = ("auto", "planar", "hungarian", "vf2", "overlay")
#: How the segmentations of a resampled sketch choose the reading they vote in (``MatchConfig.vote_rule``).
VOTE_RULES = ("score", "count")
#: Which orientations the other segmentations of a resampled sketch are matched in
#: (``MatchConfig.vote_orientations``).
VOTE_ORIENTATIONS = ("own", "first")


def _is_number(value) -> bool:
    """Whether ``value`` is a finite int or float (a bool is not a number here)."""
    return not isinstance(value, bool) and isinstance(value, (int, float)) and math.isfinite(value)


@dataclass(frozen=True, kw_only=True)
class MatchConfig:
    """Options of the matcher; the defaults are the recommended configuration.

    Attributes
    ----------
    variant : {'T4', 'T1', 'T2', 'T3', 'baseline'}
        Descriptor variant (paper Table 1): T4 = URSIM (anchors + weights).
    matcher : {'auto', 'planar', 'hungarian', 'vf2', 'overlay'}
        'planar': the seed-and-expand planar graph matcher of URSIM, built for sketches.
        'overlay': lay the maps on each other and pair what overlaps, for two metric maps
        (:mod:`ursim_core.matching.overlay`); m does not apply to it. 'auto' (default):
        'overlay' when the input is a metric map (``input_kind='metric'``) or ``scale`` is known
        (two maps of known resolutions: a sketch has none), else 'planar' (:meth:`resolved`).
    m : 'auto' or float
        Threshold on ``c`` below which two regions are "the same". ``'auto'`` picks it
        per map pair over ``m_grid`` (:mod:`ursim_core.matching.auto_m`).
    times : tuple of float
        Heat-kernel sample times.
    uniqueness_k : float
        A region is unique when ``|z| >= k`` on an attribute.
    standardise : {'own', 'model'}
        Statistics for the sketch's z-scores (released code: 'model').
    weights : {'size', 'uniqueness', 'equal'} or None
        Vertex weights; None derives them from the variant (T1/T2 equal, T3/T4 size).
        The released code used 'uniqueness' for T4.
    disparity : {'paper', 'released'}
        Anchor disparity.
    rotation_search : {'min', 'first'}
        Seed neighbour alignment over rotations (released code: 'first', a bug).
    reflections : bool
        Also try mirrored neighbour orders at the seed (not in the released code).
    size_weight_floor : float
        Added to ``z_size - min z_size`` for the size weights.
    m_grid : tuple of float
        Values of m considered by ``m='auto'``.
    auto_rule : str
        Rule used by ``m='auto'`` (see :mod:`ursim_core.matching.auto_m`).
    max_seeds : int, 'auto' or None
        Cap on the number of seeds (the lowest-c ones are kept, in their original
        order). ``'auto'`` = ``max(64, 100_000 // max(n1, n2))``: each expansion costs
        O(n), so this bounds the planar matcher to about 1e5 expanded pairs on large
        graphs; it never binds on sketch-sized graphs (6666 seeds for 15 regions,
        while 15 x 15 = 225 pairs exist). None = no cap.
    vf2_timeout : float
        Wall-clock budget of the VF2 baseline, seconds.
    signature_method : {'auto', 'eigh', 'expm'}
    position_weight : float
        beta in ``c = (c_signature + beta * d_position) / (1 + beta)`` (0 = paper); see
        :mod:`ursim_core.matching.descriptors`. Assumes the sketch keeps the map's orientation.
    position_refits : int
        Planar matcher with a position term: this many times, lay the sketch's positions on the
        metric map by a scale and shift per axis fitted to the answer's pairs, match again, and
        keep the new answer when its hypothesis score is lower (:mod:`ursim_core.matching.refit`);
        0 = positions normalised to each map's extent only. Not applied to graphs of more than 60
        regions (there its second sweep took seconds to minutes).
    signature_refit : bool
        With position refits: also match once without the position term (signatures and
        structure alone), lay the sketch on the metric map by that answer's pairs, match again
        and keep that answer when its hypothesis score is lower than the refitted one's
        (:func:`ursim_core.matching.refit.signature_start`). A start that does not depend on the
        sketch covering the metric map in proportion. Evidence: docs/options.md.
    window_start : bool
        With position refits: also lay the sketch's positions in the window of the metric map
        its free space resembles best (:func:`ursim_core.matching.template.best_window`, when it
        correlates ``WINDOW_GAIN`` better than the whole box and at least
        ``WINDOW_MIN_CORRELATION``, as the window laying asks), match
        again and keep that answer when its hypothesis score is lower
        (:func:`ursim_core.matching.oriented.window_position_starts`). A start for a sketch of
        part of the map; the other segmentations take the first one's windows. Evidence:
        docs/options.md.
    keep_refit : bool
        With position refits: True (default) keeps an orientation's refitted answer when its
        hypothesis score is lower (as above); False lets the refit only rank the orientations
        (each still ranked by its refitted answer's score) and keeps the chosen orientation's
        answer from before the refit, so with one orientation (given, or one candidate) there
        is no refit at all. Evidence: docs/options.md.
    resampling_vote : bool
        The planar matcher on a sketch that was resampled onto its wall axes and segmented in
        several resamplings (``segment_canonical(..., resampled=True)``, which ``ursim match``,
        ``ursim evaluate`` and the app use): match each segmentation and keep the pairs most of the
        answers hold (:mod:`ursim_core.matching.resampling`). Not with constraints (their region
        ids are the first segmentation's). Six matches of a turned sketch instead of one.
        Evidence: docs/options.md.
    vote_by_reading : bool
        With ``resampling_vote``: True (default) lets only the answers that read the sketch the way
        most of them do (the same mirror image, turned within a few degrees) vote on pairs, half
        of them needed; an answer in another orientation pairs regions of another reading, not
        votes for or against this one's. False: every answer votes, half of all needed.
        Evidence: docs/options.md.
    vote_rule : {'score', 'count'}
        With ``resampling_vote`` and ``vote_by_reading``: which reading the voters share. Every
        segmentation has ranked the same finalist orientations (the hypothesis score over the
        free-space overlap, ``orientation_scan``); 'score' (default) takes the reading whose mean
        rank value over all the segmentations is lowest, 'count' the reading most of their own
        choices fall in (ties: the earliest answer's). Evidence: docs/options.md.
    vote_segmentations : int
        With ``resampling_vote``: how many of a turned sketch's segmentations vote (at most the
        six ``segment_canonical(..., resampled=True)`` makes), the first and then its resamplings:
        not turned back, then in the order of ``segmentation.canonical.RESAMPLING_OFFSETS``.
        Evidence: docs/options.md.
    vote_signature_refit : bool
        With ``resampling_vote`` and ``signature_refit``: whether the other segmentations of a
        turned sketch refit from the signatures too (True, the default) or only the first does
        (each still refits by its own pairs). Evidence: docs/options.md.
    vote_orientations : {'own', 'first'}
        With ``resampling_vote``: the orientations the other segmentations of a turned sketch are
        matched in. 'own' (the default): their own candidates (from their label image's wall
        angle) nearest to the first segmentation's finalists, a fraction of a degree from them.
        'first': the first one's finalists as they are, so no other label image has its wall
        angle measured: faster, not the default. Evidence: docs/options.md.
    hypothesis_score : {'signature', 'substitutions', 'structure'}
        Planar hypothesis score: 'structure' = the released code's structural cost;
        'substitutions' = plus ``score_weight`` per matched pair with ``c > m`` (the
        paper's "replace: 1"); 'signature' = plus ``score_weight * sum of c`` over the
        matched pairs. Also used to score Hungarian and VF2 results.
    score_weight : float
        Weight of the pair term of the hypothesis score.
    orientation : 'any', 'upright' or float
        How the sketch is turned relative to the metric map. 'any' (default): unknown; the
        matcher tries the turns that bring the sketch's walls parallel to the metric map's
        (4 quarter turns of the wall-angle difference) and keeps the lowest-scoring answer
        (:mod:`ursim_core.matching.orientation`). 'upright': drawn in the metric map's
        orientation. A number: the sketch is brought to the metric map by turning it that
        many degrees counter-clockwise (after mirroring when ``mirrored``). It undoes how the
        sketch was drawn: a sketch drawn turned 90 degrees counter-clockwise from the map is
        ``orientation=270`` (or ``-90``), the inverse of the turn that
        :class:`ursim_core.evaluation.augment.Orientation` applies to an upright sketch.
    mirrored : bool or None
        Whether the sketch is a left-right mirror image of the map; None (default) = unknown,
        both are tried with ``orientation='any'`` (with 'upright' or a number, None = no). For
        the overlay matcher None means no: two metric maps are both seen from above, so neither
        is a mirror image of the other (pass True to try mirror images all the same).
    orientation_overlap : float
        With ``orientation='any'``, the orientations are ranked by their hypothesis score divided
        by the free-space overlap (intersection over union) of the sketch fitted onto the metric
        map in that orientation, raised to this power (:mod:`ursim_core.matching.alignment`);
        0 = by the score alone. Needs the label images (segmentations, not bare graphs); graphs
        of more than 60 regions are screened by assignment cost alone.
    orientation_finalists : int
        With ``orientation='any'`` and the automatic m: the candidate orientations are screened
        on every second m of the grid, and this many of the best get the full sweep and the
        refit, which decide. Evidence: docs/options.md.
    adjacency_penalty : float
        With ``orientation='any'``, each finalist reading's rank value is multiplied by 1 + this
        times the share of its answer's sketch adjacencies that the answer breaks
        (:func:`~ursim_core.matching.orientation.broken_adjacencies`); 0 = not. A half turn or
        mirror image of a partial sketch of rooms along a corridor can fit the room sizes better
        than the right reading, but joins rooms that are not neighbours. Evidence: docs/options.md.
    door_penalty : float
        With ``orientation='any'``, each finalist reading's rank value is also multiplied by 1 +
        this times how far its answer's regions touch their neighbours from where their partners
        touch theirs (:func:`~ursim_core.matching.orientation.misplaced_doors`), when some
        finalist's is below ``orientation.DOOR_EVIDENCE`` (the doors were drawn where they are);
        0 = not. The same half turn or mirror image puts each room's door at the other end of its
        wall. Evidence: docs/options.md.
    window_reading_margin : float
        With ``orientation='any'`` and a window laying (``elastic_laying``), a finalist reading in
        which the sketch resembles a part of the metric map (its best window correlates clearly
        better than the map's whole box) by at least this much more correlation than in the reading
        ranked best is taken instead (:func:`~ursim_core.matching.oriented.window_reading`); 0 =
        never. Evidence: docs/options.md.
    auto_partial : bool
        When the sketch, read as the matcher reads it, is laid in the window of the metric map it
        resembles clearly better than the whole (the window laying of ``elastic_laying``:
        ``template.WINDOW_GAIN`` better than the whole box, at least ``WINDOW_MIN_CORRELATION``),
        match it again as a sketch of part of the map, with :data:`PARTIAL_SKETCH`'s options
        (what ``ursim match --partial`` tells). The answer's config then holds them, and its
        reason says so. Evidence: docs/options.md.
    scale : float or None
        Metric-map pixels per sketch pixel when known (1 for two robot maps of the same
        resolution), for the overlay matcher: it then searches any placement, so either map may
        cover only part of the other. None: unknown; both maps are taken to cover the same extent.
    overlay_min_iou : float
        The overlay matcher pairs regions whose intersection over union is at least this.
    overlay_angle_step : float
        With ``orientation='any'``, the overlay matcher also tries each candidate orientation turned
        by one and two such steps (degrees) either way, keeping the best correlation; 0 = the
        wall angles' quarter turns only. Evidence: docs/options.md.
    input_kind : {'sketch', 'metric'} or None
        What the input map is: 'metric' (a robot map, a floor plan drawn to scale) makes
        ``matcher='auto'`` the overlay matcher; None (default) = unknown, taken as a sketch unless
        ``scale`` is known.
    elastic : {'off', 'alone', 'completed'}
        With 'alone' or 'completed' the planar matcher reads the sketch's orientation, and the
        answer's pairs are those of the sketch laid on the metric map by its box and bent by an
        optical flow between the two maps (:mod:`ursim_core.matching.elastic`), regions paired at
        ``overlay_min_iou``; 'completed' adds the planar answer's pairs of regions left unpaired on
        both sides. Planar matcher, label images and sketch-sized maps (at most 60 regions each) only.
    elastic_laying : {'boxes', 'boxes_or_answer', 'window', 'window_or_answer', 'boxes_or_window'}
        Where the sketch is laid before it is bent: 'window' (default), box onto box, or in the
        window of the metric map where it correlates clearly better than over the whole box
        (:func:`~ursim_core.matching.layings.window_laying`): a partial sketch laid box onto box
        is stretched over the whole map; 'boxes', box onto box only; 'boxes_or_answer' and
        'window_or_answer', also by a scale and a shift per axis fitted to the planar answer's
        pairs (:func:`~ursim_core.matching.layings.answer_laying`), the laying whose bent sketch
        lands more on the metric map's free space giving the pairs (a second optical flow);
        'boxes_or_window', box onto box or the best window whatever its margin, whichever lands
        more (:data:`ELASTIC_LAYING_RULES`). Evidence: docs/options.md.
    elastic_partners : {'neighbours', 'all'}
        A sketch region the laid sketch pairs with several metric regions keeps one (its partner in
        the graph answer, else the one it overlaps most) and those that neighbour a kept one on the
        metric map ('neighbours', default: a drawn room bent over two rooms with a wall between
        belongs to one of them), or all of them ('all', before round 53;
        :func:`~ursim_core.matching.laid.joined_partners`). Evidence: docs/options.md.

    Examples
    --------
    >>> upright = MatchConfig(orientation="upright")  # a sketch drawn in the metric map's orientation
    >>> upright.orientation, upright.m, upright.resolved().matcher
    ('upright', 'auto', 'planar')
    >>> MatchConfig.paper().m, MatchConfig.paper().replace(m=0.1).m  # the paper's method at another m
    (0.15, 0.1)
    >>> MatchConfig(m=-0.1)
    Traceback (most recent call last):
    ...
    ursim_core.errors.ParameterError: field 'm': must be 'auto' or a non-negative number, not -0.1
    """

    variant: str = "T4"
    matcher: str = "auto"
    m: Any = "auto"
    times: tuple = DEFAULT_TIMES
    uniqueness_k: float = 1.0
    standardise: str = "own"
    weights: str | None = None
    disparity: str = "paper"
    rotation_search: str = "min"
    reflections: bool = False
    size_weight_floor: float = SIZE_WEIGHT_FLOOR
    m_grid: tuple = M_GRID
    auto_rule: str = "score"
    max_seeds: Any = "auto"
    vf2_timeout: float = 2.0
    signature_method: str = "auto"
    position_weight: float = 2.0
    position_refits: int = 1
    signature_refit: bool = True
    window_start: bool = False
    keep_refit: bool = True
    resampling_vote: bool = True
    vote_by_reading: bool = True
    vote_rule: str = "score"
    vote_segmentations: int = 6
    vote_signature_refit: bool = True
    vote_orientations: str = "own"
    hypothesis_score: str = "signature"
    score_weight: float = 8.0
    orientation: Any = "any"
    mirrored: bool | None = None
    orientation_overlap: float = 1.0
    orientation_finalists: int = 4
    adjacency_penalty: float = 2.0
    door_penalty: float = 1.0
    window_reading_margin: float = 0.0
    auto_partial: bool = True
    scale: float | None = None
    overlay_min_iou: float = 0.15
    overlay_angle_step: float = 2.0
    input_kind: str | None = None
    elastic: str = "completed"
    elastic_laying: str = "window"
    elastic_partners: str = "neighbours"

    def __post_init__(self):
        choices = {
            "variant": VARIANTS,
            "matcher": MATCHERS,
            "standardise": ("own", "model"),
            "weights": (None, "size", "uniqueness", "equal"),
            "disparity": ("paper", "released"),
            "rotation_search": ("min", "first"),
            "signature_method": ("auto", "eigh", "expm"),
            "hypothesis_score": ("signature", "substitutions", "structure"),
            "vote_rule": VOTE_RULES,
            "vote_orientations": VOTE_ORIENTATIONS,
            "elastic": ELASTIC_RULES,
            "elastic_laying": ELASTIC_LAYINGS,
            "elastic_partners": ELASTIC_PARTNERS,
        }
        for name, allowed in choices.items():
            if getattr(self, name) not in allowed:
                raise ParameterError(f"must be one of {allowed}, not {getattr(self, name)!r}", field=name)
        if self.m != "auto" and not (_is_number(self.m) and self.m >= 0):
            raise ParameterError(f"must be 'auto' or a non-negative number, not {self.m!r}", field="m")
        if self.max_seeds not in ("auto", None) and (not isinstance(self.max_seeds, int) or self.max_seeds < 1):
            raise ParameterError(
                f"must be 'auto', None or a positive integer, not {self.max_seeds!r}", field="max_seeds"
            )
        for name in (
            "position_weight",
            "score_weight",
            "uniqueness_k",
            "size_weight_floor",
            "vf2_timeout",
            "orientation_overlap",
            "adjacency_penalty",
            "door_penalty",
            "window_reading_margin",
            "overlay_min_iou",
            "overlay_angle_step",
        ):
            value = getattr(self, name)
            if not (_is_number(value) and value >= 0):
                raise ParameterError(f"must be a non-negative number, not {value!r}", field=name)
        if self.orientation not in ORIENTATIONS and not _is_number(self.orientation):
            raise ParameterError(
                f"must be 'any', 'upright' or a number of degrees, not {self.orientation!r}", field="orientation"
            )
        if self.scale is not None and not (_is_number(self.scale) and self.scale > 0):
            raise ParameterError(f"must be a positive number or null, not {self.scale!r}", field="scale")
        if self.input_kind not in (None, "sketch", "metric"):
            raise ParameterError(f"must be 'sketch', 'metric' or null, not {self.input_kind!r}", field="input_kind")
        if self.mirrored not in (None, True, False):
            raise ParameterError(
                f"must be True, False or None (true, false or null in JSON), not {self.mirrored!r}", field="mirrored"
            )
        for name, smallest, wording in (
            ("position_refits", 0, "a non-negative integer"),
            ("vote_segmentations", 1, "a positive integer"),
            ("orientation_finalists", 1, "a positive integer"),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < smallest:
                raise ParameterError(f"must be {wording}, not {value!r}", field=name)
        for name in (
            "signature_refit",
            "window_start",
            "auto_partial",
            "keep_refit",
            "resampling_vote",
            "vote_by_reading",
            "vote_signature_refit",
        ):
            if not isinstance(getattr(self, name), bool):
                raise ParameterError(f"must be true or false, not {getattr(self, name)!r}", field=name)
        if not self.times:
            raise ParameterError("needs at least one time", field="times")
        if not self.m_grid:
            raise ParameterError("needs at least one value", field="m_grid")
        if self.auto_rule not in AUTO_RULE_NAMES:
            raise ParameterError(f"must be one of {AUTO_RULE_NAMES}, not {self.auto_rule!r}", field="auto_rule")

    @classmethod
    def released(cls, **overrides) -> MatchConfig:
        """Every option of the released C++ code on (original_code.md §1.14).

        Sketch standardised with the metric map's statistics, uniqueness-score weights,
        released anchor disparity, first-rotation behaviour, no reflections, m = 0.125
        (its best single fixed m on the KTH sketches). Segmentation options (robot
        parameters for sketches, non-zero-is-free binarisation) belong to the caller.

        Examples
        --------
        >>> MatchConfig.released().weights
        'uniqueness'
        """
        values = dict(
            variant="T4",
            matcher="planar",
            m=0.125,
            standardise="model",
            weights="uniqueness",
            disparity="released",
            rotation_search="first",
            reflections=False,
            position_weight=0.0,
            position_refits=0,
            elastic="off",
            adjacency_penalty=0.0,
            door_penalty=0.0,
            signature_refit=False,
            resampling_vote=False,
            hypothesis_score="structure",
            score_weight=0.0,
            orientation="upright",
            mirrored=False,
        )
        values.update(overrides)
        return cls(**values)

    @classmethod
    def paper(cls, **overrides) -> MatchConfig:
        """The method as the paper describes it.

        Own-map standardisation, standardised sizes as weights, mean-|dz| disparity,
        minimum-distance rotation, no position term, hypothesis score = structural cost
        plus 1 per substituted pair (the paper's edit costs), m = 0.15 (the paper's best
        fixed m, Section 6.4).

        Examples
        --------
        >>> MatchConfig.paper().position_weight, MatchConfig.paper().hypothesis_score
        (0.0, 'substitutions')
        """
        values = dict(
            variant="T4",
            matcher="planar",
            m=0.15,
            standardise="own",
            weights=None,
            disparity="paper",
            rotation_search="min",
            reflections=False,
            position_weight=0.0,
            position_refits=0,
            elastic="off",
            adjacency_penalty=0.0,
            door_penalty=0.0,
            signature_refit=False,
            resampling_vote=False,
            hypothesis_score="substitutions",
            score_weight=1.0,
            orientation="upright",
            mirrored=False,
        )
        values.update(overrides)
        return cls(**values)

    def resolved(self) -> MatchConfig:
        """This configuration with its automatic choices made: what the matcher runs.

        ``matcher='auto'`` becomes 'overlay' when the input is a metric map or ``scale`` is known,
        and 'planar' otherwise; for the overlay matcher an unknown ``mirrored`` becomes False.

        Examples
        --------
        >>> MatchConfig().resolved().matcher, MatchConfig(scale=1.0).resolved().matcher
        ('planar', 'overlay')
        >>> MatchConfig(scale=1.0).resolved().mirrored, MatchConfig(input_kind="metric").resolved().matcher
        (False, 'overlay')
        """
        matcher = self.matcher
        if matcher == "auto":
            metric = self.input_kind == "metric" or (self.input_kind is None and self.scale is not None)
            matcher = "overlay" if metric else "planar"
        mirrored = False if matcher == "overlay" and self.mirrored is None else self.mirrored
        if (matcher, mirrored) == (self.matcher, self.mirrored):
            return self
        return dataclasses.replace(self, matcher=matcher, mirrored=mirrored)

    def with_resolutions(self, sketch_resolution: float | None, metric_resolution: float | None) -> MatchConfig:
        """This configuration with ``scale`` read from the maps' resolutions (metres per pixel).

        Two georeferenced maps (ROS YAML) tell their relative scale: metric pixels per input
        pixel = input resolution / metric resolution. It is filled in only when the matcher
        uses it ('auto' or 'overlay') and no scale was given. An input with a resolution is a
        metric map (``input_kind``, when not given); a map without one (a sketch, a bare image)
        changes nothing. A ratio that is not a finite positive number raises ParameterError.

        Examples
        --------
        >>> MatchConfig().with_resolutions(0.1, 0.05).scale
        2.0
        >>> MatchConfig().with_resolutions(None, 0.05).scale is None
        True
        >>> MatchConfig().with_resolutions(0.05, None).input_kind
        'metric'
        """
        config = self
        if sketch_resolution and config.input_kind is None:
            config = config.replace(input_kind="metric")
        if config.matcher not in ("auto", "overlay") or config.scale is not None:
            return config
        if not sketch_resolution or not metric_resolution:
            return config
        scale = float(sketch_resolution) / float(metric_resolution)
        if not (math.isfinite(scale) and scale > 0):
            # Each resolution was accepted alone; their ratio overflows or underflows.
            raise ParameterError(
                f"the maps' resolutions ({sketch_resolution:g} and {metric_resolution:g} m/px) give no "
                f"usable scale (their ratio is {scale:g})",
                field="scale",
            )
        return config.replace(scale=scale)

    def replace(self, **changes) -> MatchConfig:
        """A copy with some fields changed (validated like a new config).

        Examples
        --------
        >>> MatchConfig().replace(m=0.2).m
        0.2
        """
        return dataclasses.replace(self, **changes)

    @property
    def effective_weights(self) -> str | None:
        """The weights actually used (None for the baseline variant)."""
        if self.variant == "baseline":
            return None
        if self.weights is not None:
            return self.weights
        return {"T1": "equal", "T2": "equal", "T3": "size", "T4": "size"}[self.variant]
