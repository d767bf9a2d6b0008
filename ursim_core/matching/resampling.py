"""One answer from several segmentations of a resampled sketch: a vote over their answers.

A sketch whose walls are off the image axes is resampled onto them before it is segmented
(:mod:`ursim_core.segmentation.canonical`), and MAORIS's regions change with the resampling: turned
by a degree more or less, a hall splits or a door closes. On the 18 KTH sketches turned by 15, 30,
..., 345 degrees, one segmentation per turned sketch scored 0.69 mean F1 where the better of two
scored 0.76 and the best of four 0.79 (round 30, study scripts). No score of a single answer picks
the better segmentation (the hypothesis cost: 0.70; the sketch area matched: 0.72), but the
answers agree where the segmentations do: :func:`vote_pairs` carries every answer onto the first
segmentation's regions and keeps the pairs that at least half of them hold (:func:`voted_result`):
0.682 -> 0.720 mean F1 and 0.695 -> 0.720 place accuracy on the 360 resampled turns. Since round
32 only the answers that read the sketch the way most of them do vote on pairs
(:func:`most_common_reading`, ``MatchConfig.vote_by_reading``). Since round 33 ten segmentations
vote instead of six (``MatchConfig.vote_segmentations``): the vote's matches had become cheap
enough for it. Since round 37 eight vote, and the reading they vote in is the one all of them rank
best on the whole, not the one most of them chose (:func:`lowest_scored_reading`,
``MatchConfig.vote_rule``). Since round 39 six vote again, as leave-one-sketch-out chose once the
turned sketches were smoothed (round 38).

``segment_canonical(..., resampled=True)`` makes the other segmentations
(``Segmentation.resampled``); :func:`ursim_core.matching.prepare` prepares each when
``MatchConfig.resampling_vote`` is on (the planar matcher, no constraints), and
:func:`ursim_core.matching.match_prepared` matches them at the same m and votes
(:func:`voted_result`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ursim_core.matching.kernels import correspondences_compiled

__all__ = [
    "Resampled",
    "VoteReading",
    "region_correspondence",
    "region_correspondences",
    "vote_pairs",
    "voted_result",
    "vote_reading",
    "most_common_reading",
    "lowest_scored_reading",
    "mean_rank_values",
    "with_resampled",
    "voted_answer",
]


@dataclass(frozen=True)
class Resampled:
    """The other segmentations of a sketch, prepared for matching.

    Attributes
    ----------
    labels : ndarray of int32
        The label image of the sketch's own segmentation, the one the answer is given in.
    variants : tuple of (ndarray, Prepared)
        Each other segmentation's label image (same frame) and its preparation.
    correspondences : tuple of dict
        :func:`region_correspondence` of ``labels`` with itself, then with each variant's
        labels: computed once, since a sweep over m votes once per m.
    reading : VoteReading or None
        Who votes, in which orientation (:func:`vote_reading`): it depends on the preparations
        alone, not on m, so it is found once too.
    """

    labels: np.ndarray
    variants: tuple
    correspondences: tuple = ()
    reading: Any = None


@dataclass(frozen=True)
class VoteReading:
    """The reading a vote is held in (:func:`vote_reading`).

    Attributes
    ----------
    voters : list of int
        The answers that vote (indices, the first segmentation's answer 0).
    orientation : (float, bool)
        The orientation the voted answer reports.
    scan : dict
        The vote's ``orientation_scan``: each of the first answer's candidates, its reading's mean
        rank value over the answers (what the score rule ranks).
    """

    voters: list
    orientation: tuple
    scan: dict


def region_correspondence(labels: np.ndarray, other: np.ndarray) -> dict[int, int]:
    """For each region of ``other``, the region of ``labels`` it overlaps most (pixels of both).

    Two segmentations of one map, in one frame. A region that overlaps no region of ``labels``
    has no entry; ties go to the lower region id.

    Examples
    --------
    >>> a = np.array([[1, 1, 2, 2]]); b = np.array([[5, 5, 5, 7]])
    >>> region_correspondence(a, b)
    {5: 1, 7: 2}
    """
    return region_correspondences(labels, [other])[0]


def region_correspondences(labels: np.ndarray, others: Sequence[np.ndarray]) -> list[dict[int, int]]:
    """:func:`region_correspondence` of ``labels`` with each of ``others``: the pixels in a region
    of ``labels`` are found once for all of them.

    Examples
    --------
    >>> a = np.array([[1, 1, 2, 2]])
    >>> region_correspondences(a, [np.array([[5, 5, 5, 7]]), np.array([[0, 3, 3, 3]])])
    [{5: 1, 7: 2}, {3: 2}]
    """
    # A joint histogram of (other region, region) over the pixels in a region of both (ids > 0),
    # one integer key per pixel: a bincount, linear in the pixels. np.unique's sort was most of a
    # vote's cost (round 32). Regions cover about a fifth of a turned KTH sketch's image, so the
    # histograms read only those pixels, found once for the first segmentation and the nine others
    # (round 35: the ten correspondences of a KTH pair turned by 30 degrees 26-28 -> 13-14 ms, the
    # same ones).
    compiled = correspondences_compiled(labels, others)
    if compiled is not None:
        # The histograms counted by runs over the stretches of region pixels, without NumPy's
        # temporaries (round 41: 7.8 -> 2.4 ms a turned KTH pair); the same dicts, a test
        # compares them.
        return compiled
    labels = np.asarray(labels).ravel()
    inside = np.flatnonzero(labels > 0)
    regions = labels[inside]
    stride = int(regions.max()) + 1 if regions.size else 1
    found = []
    for other in others:
        other = np.asarray(other).ravel()[inside]
        both = other > 0
        theirs, ours = other[both], regions[both]
        if ours.size == 0:
            found.append({})
            continue
        keys = theirs.astype(np.intp) * stride + ours
        counts = np.bincount(keys, minlength=(int(theirs.max()) + 1) * stride).reshape(-1, stride)
        present = np.flatnonzero(counts.any(axis=1))
        # argmax takes the first of equal counts: ties go to the lower region id.
        best = counts[present].argmax(axis=1)
        found.append(dict(zip(present.tolist(), best.tolist(), strict=True)))
    return found


def vote_pairs(
    labels: np.ndarray,
    answers: Sequence[tuple[np.ndarray, Sequence]],
    *,
    quorum: int,
    correspondences: Sequence[dict] | None = None,
) -> list:
    """The pairs that at least ``quorum`` answers hold, on the regions of ``labels``.

    Parameters
    ----------
    labels : ndarray of int
        The segmentation the voted pairs are given in.
    answers : sequence of (label image, pairs)
        Each answer's segmentation of the same map (same frame) and its (sketch region, metric
        region) pairs; each sketch region is carried to the region of ``labels`` it overlaps
        most (:func:`region_correspondence`).
    quorum : int
        Votes a pair needs.
    correspondences : sequence of dict, optional
        Each answer's :func:`region_correspondence` with ``labels``, when known already.

    Returns
    -------
    list of (int, int)
        One to one: pairs by decreasing votes, ties in the order the answers first hold them,
        each kept unless one of its regions is already paired.

    Examples
    --------
    The second segmentation splits region 1 of ``base`` (its regions 1 and 2) and calls region 2
    3; its answer pairs region 3 elsewhere, which one vote does not carry:

    >>> base = np.array([[1, 1, 2, 2]]); split = np.array([[1, 2, 3, 3]])
    >>> vote_pairs(base, [(base, [(1, 10), (2, 20)]), (split, [(1, 10), (3, 21)]),
    ...                   (base, [(2, 20)])], quorum=2)
    [(1, 10), (2, 20)]
    """
    votes: Counter = Counter()
    order: dict = {}  # each pair's first appearance: the tie order
    for index, (other, pairs) in enumerate(answers):
        carried = correspondences[index] if correspondences else region_correspondence(labels, other)
        held = [(carried[a], b) for a, b in pairs if a in carried]
        for pair in held:
            order.setdefault(pair, len(order))
        votes.update(set(held))
    chosen, sketch_used, metric_used = [], set(), set()
    for pair, count in sorted(votes.items(), key=lambda item: (-item[1], order[item[0]])):
        if count >= quorum and pair[0] not in sketch_used and pair[1] not in metric_used:
            chosen.append(pair)
            sketch_used.add(pair[0])
            metric_used.add(pair[1])
    return chosen


def voted_result(
    first: Any,
    labels: np.ndarray,
    answers: Sequence[tuple[np.ndarray, Any]],
    *,
    correspondences=None,
    reading: VoteReading | None = None,
) -> Any:
    """``first`` (a MatchResult in the segmentation ``labels``) with the pairs that at least half of
    the answers hold (``first`` included, as the answer of ``labels``); its other fields stay the
    first answer's.

    With ``first.config.vote_by_reading`` (the default) the voters are the answers of one reading,
    and the orientation is that of the earliest of them. The reading is the one ranked best over
    all the answers' orientation scans (:func:`lowest_scored_reading`, ``vote_rule='score'``, the
    default) or the one most of them chose (:func:`most_common_reading`, ``vote_rule='count'``;
    ties: the first's). An answer that reads the sketch turned by a quarter turn or
    mirrored pairs regions of another reading: counted against this reading's pairs (as one of
    all six, round 30), it made a pair that half of the same reading held fall short. The 18 KTH
    sketches turned by 15, 30, ..., 345 degrees (``ursim evaluate ... --cross-validate
    vote_by_reading=true,false``, round 32): true in every fold, 52 of 864 runs changed, mean F1
    0.7253 -> 0.7297, place accuracy 0.7287 -> 0.7361 (04 0.44 -> 0.49, 11 0.96 -> 0.99, 01 0.70 ->
    0.68). Without it every answer votes, half of all needed, and the orientation is the one most
    of them read exactly (ties: the first's).

    Half, not a majority: of six answers a majority (four) left regions unpaired that the single
    answer had paired, and place accuracy fell (the 360 resampled turns of the 18 KTH sketches by
    15-345 degrees, a study script, round 30: F1 / place accuracy 0.682 / 0.695 with one
    segmentation, 0.721 / 0.689 with four votes, 0.720 / 0.720 with three, 0.714 / 0.726 with two;
    the quorum was chosen on these sketches). On generated pairs
    not used in the design (``ursim bench invariance`` seeds 32-63) three votes gave 0.862 mean F1,
    four 0.858, one segmentation 0.861. ``correspondences``: as :func:`vote_pairs` takes them, ``first``'s
    (``labels`` with itself) first. ``reading``: :func:`vote_reading` of the answers, when known
    already (it does not depend on m)."""
    every = [(labels, first), *answers]
    if reading is None:
        results = [result for _, result in every]
        reading = vote_reading(
            first.config, [result.orientation for result in results], [result.orientation_scan for result in results]
        )
    voters = reading.voters
    pairs = vote_pairs(
        labels,
        [(every[index][0], every[index][1].pairs) for index in voters],
        quorum=(len(voters) + 1) // 2,
        correspondences=[correspondences[index] for index in voters] if correspondences else None,
    )
    return dataclasses.replace(
        first,
        pairs=pairs,
        orientation=tuple(reading.orientation),
        resampling_votes=len(every),
        orientation_scan=reading.scan,
    )


def vote_reading(config: Any, orientations: Sequence[tuple], scans: Sequence[dict]) -> VoteReading:
    """Which answers vote and in which orientation, from each answer's ``(degrees, mirrored)``
    orientation and ``orientation_scan`` (the first segmentation's first), as :func:`voted_result`
    describes it for ``config`` (``vote_by_reading``, ``vote_rule``).

    Examples
    --------
    >>> from types import SimpleNamespace as Config
    >>> scans = [{(0.0, False): 0.3, (90.0, True): 0.5}, {(0.2, False): 0.4, (90.2, True): 0.35}]
    >>> reading = vote_reading(Config(vote_by_reading=True, vote_rule="score"), [(0.0, False), (90.2, True)], scans)
    >>> reading.voters, reading.orientation, reading.scan
    ([0], (0.0, False), {(0.0, False): 0.35, (90.0, True): 0.425})
    """
    if config.vote_by_reading:
        if config.vote_rule == "score":
            voters = lowest_scored_reading(orientations, scans)
        else:
            voters = most_common_reading(orientations)
        orientation = orientations[voters[0]]
    else:
        voters = list(range(len(orientations)))
        readings = Counter(tuple(orientation) for orientation in orientations)
        orientation = max(readings, key=lambda reading: (readings[reading], reading == tuple(orientations[0])))
    keys = list(scans[0])
    return VoteReading(voters, tuple(orientation), dict(zip(keys, mean_rank_values(keys, scans), strict=True)))


def most_common_reading(orientations: Sequence[tuple[float, bool]]) -> list[int]:
    """The indices of the ``(degrees, mirrored)`` orientations that read a sketch the way most of
    them do: the same mirror flag, turned less than
    :data:`~ursim_core.matching.orientation.SAME_READING` degrees apart. Ties go to the reading of
    the earliest orientation.

    The answers of several segmentations of one sketch are found in orientations a fraction of a
    degree apart when they read it alike (their wall angles differ by that much), and a quarter
    turn or a mirror image apart when not.

    Examples
    --------
    >>> most_common_reading([(90.4, False), (270.1, False), (269.6, False), (90.0, True)])
    [1, 2]
    >>> most_common_reading([(0.5, False), (180.0, False)])
    [0]
    """

    from ursim_core.matching.orientation import same_reading  # imports networkx; this module does not

    groups = [[j for j, other in enumerate(orientations) if same_reading(one, other)] for one in orientations]
    return max(groups, key=len)  # max keeps the first of equal lengths: the earliest reading's


def lowest_scored_reading(orientations: Sequence[tuple[float, bool]], scans: Sequence[dict]) -> list[int]:
    """The indices of the ``(degrees, mirrored)`` orientations in the reading whose mean score over
    all the ``scans`` is lowest (``MatchConfig(vote_rule="score")``).

    ``scans[k]`` is the k-th answer's ``orientation_scan``: the rank value (lower is better) of
    every orientation its segmentation tried. A reading's value in a scan is the lowest of the scan's
    orientations in that reading (:data:`~ursim_core.matching.orientation.SAME_READING`); its score
    is the mean over the scans that tried it (:func:`mean_rank_values`). Only readings some answer
    chose are candidates. Ties, and readings no scan tried, go by :func:`most_common_reading` (more
    answers, then the earliest).

    Examples
    --------
    Three answers, two of them mirrored; the unmirrored reading is ranked better on the whole:

    >>> scans = [{(0.2, False): 0.30, (90.0, True): 0.31}, {(0.0, False): 0.33, (90.1, True): 0.32},
    ...          {(0.1, False): 0.30, (89.9, True): 0.32}]
    >>> lowest_scored_reading([(0.2, False), (90.1, True), (89.9, True)], scans)
    [0]
    >>> most_common_reading([(0.2, False), (90.1, True), (89.9, True)])
    [1, 2]
    """
    from ursim_core.matching.orientation import same_reading  # imports networkx; this module does not

    means = mean_rank_values(orientations, scans)
    best = None
    for index, reading in enumerate(orientations):
        group = [j for j, other in enumerate(orientations) if same_reading(reading, other)]
        key = (means[index], -len(group), index)
        if best is None or key < best[0]:
            best = (key, group)
    return best[1] if best else []


def mean_rank_values(readings: Sequence[tuple[float, bool]], scans: Sequence[dict]) -> list[float]:
    """For each ``(degrees, mirrored)`` reading, its mean rank value over the ``scans`` that tried it
    (inf when none did). A reading's value in a scan is the lowest of the scan's orientations in that
    reading (:data:`~ursim_core.matching.orientation.SAME_READING`).

    Examples
    --------
    >>> mean_rank_values([(0.0, False), (90.0, True)], [{(0.2, False): 0.3}, {(359.9, False): 0.5}])
    [0.4, inf]
    """
    from ursim_core.matching.orientation import same_reading  # imports networkx; this module does not

    means = []
    for reading in readings:
        values = [
            min(value for tried, value in scan.items() if same_reading(tried, reading))
            for scan in scans
            if any(same_reading(tried, reading) for tried in scan)
        ]
        means.append(sum(values) / len(values) if values else math.inf)
    return means


def with_resampled(prepared: Any, sketch_seg: Any, metric_seg: Any, prepare_one) -> Any:
    """``prepared`` with the sketch's other segmentations prepared too (``Prepared.resampled``),
    when it has some (``Segmentation.resampled``), the configuration votes
    (``resampling_vote``) with the planar matcher, and no constraints fix region ids.

    ``prepare_one(sketch_seg, metric_seg, config, *, orientations, overlaps, windows) -> Prepared``
    prepares one segmentation (:func:`ursim_core.matching.prepare` without the vote) in the
    orientations nearest to ``orientations`` (all of its own candidates when None), with the
    free-space overlaps ``overlaps`` and best windows ``windows`` already measured.

    The other segmentations are matched in the orientations the first one's search kept as
    finalists (``Prepared.orientation_scan``), not screened in all eight again: the orientation
    is still voted on, at two thirds of the time. On the 18 KTH sketches turned by 15, 30, ...,
    345 degrees (``ursim evaluate``, automatic m, both annotators, 864 runs) 32 runs changed, mean
    F1 0.7268 -> 0.7253, place accuracy 0.7291 -> 0.7287; generated pairs (``ursim bench
    invariance``) seeds 0-31 identical; a KTH pair turned by 30 degrees 310 -> 205 ms
    (interleaved x2, round 31).

    They take the free-space overlaps of their orientations from the first one's
    (``Prepared.orientation_overlaps``) instead of fitting the sketch again: the same frame and
    the same sketch up to resampling noise. On those 864 runs 18 changed, mean F1 0.7297 -> 0.7307,
    place accuracy 0.7361 -> 0.7384 (in sample); a KTH pair turned by 30 degrees 147 -> 115 ms
    (round 33).

    With ``MatchConfig(vote_signature_refit=False)`` only the first segmentation refits from the
    signatures alone: a turned KTH pair about 15 % faster, held out the same on KTH, but lower on
    held-out generated pairs (round 35, see the option)."""
    config = prepared.config
    others = getattr(sketch_seg, "resampled", ())
    others = tuple(others)[: config.vote_segmentations - 1]
    if not others or not config.resampling_vote or config.matcher != "planar" or prepared.constraints is not None:
        return prepared
    finalists = tuple(prepared.orientation_scan) or None
    overlaps = prepared.orientation_overlaps
    # The refit's start from the signatures alone (``signature_refit``) costs a sweep and a refit
    # per mirror flag: ``vote_signature_refit=False`` leaves it to the first segmentation.
    others_config = config if config.vote_signature_refit else config.replace(signature_refit=False)
    windows = prepared.orientation_windows
    variants = tuple(
        (
            other.labels,
            prepare_one(
                other,
                metric_seg,
                others_config,
                orientations=finalists,
                overlaps=overlaps,
                windows=windows,
                window_starts=prepared.orientation_window_starts,
            ),
        )
        for other in others
    )
    labels = sketch_seg.labels
    # The first answer's is ``labels`` with itself (the identity on its regions), in the same pass.
    correspondences = tuple(region_correspondences(labels, [labels, *(other for other, _ in variants)]))
    # Every answer, at any m, is in its preparation's orientation and carries its scan.
    preparations = [prepared, *(variant for _, variant in variants)]
    reading = vote_reading(
        config,
        [preparation.orientation for preparation in preparations],
        [preparation.orientation_scan for preparation in preparations],
    )
    resampled = Resampled(labels=labels, variants=variants, correspondences=correspondences, reading=reading)
    return dataclasses.replace(prepared, resampled=resampled)


def voted_answer(prepared: Any, m: float | None, match_one) -> Any:
    """The answer of ``prepared`` at ``m`` voted with its other segmentations' answers at the same
    m (each its own automatic m when ``m`` is None); ``match_one(prepared, m) -> MatchResult``."""
    first = match_one(prepared, m)
    resampled = prepared.resampled
    answers = [(labels, match_one(variant, m)) for labels, variant in resampled.variants]
    return voted_result(
        first, resampled.labels, answers, correspondences=resampled.correspondences, reading=resampled.reading
    )
