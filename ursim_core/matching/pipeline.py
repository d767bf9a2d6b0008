"""URSIM matching of a sketch segmentation to a metric segmentation.

Entry point: :func:`match` ``(sketch_seg, metric_seg, *, config=MatchConfig()) -> MatchResult``.
For sweeping m, :func:`prepare` computes everything that does not depend on m once (attributes,
anchors, weights, signatures, the ``c`` matrix, neighbour orders) and :func:`match_prepared` runs
one matcher at one m.

Configuration (:class:`MatchConfig`): every departure of the released C++ code and every extension
beyond the paper is a named option, so each can be measured. :meth:`MatchConfig.paper` is the
paper's method as published, :meth:`MatchConfig.released` turns every released-code option on, and
the default ``MatchConfig()`` is the paper's method plus the two extensions that the KTH evidence
supports (position-aware comparison, signature-aware hypothesis score) and the automatic m.
See ``ursim_core.matching.descriptors`` (signatures), ``ursim_core.matching.planar`` (Algorithm 1),
``ursim_core.matching.baselines`` (Hungarian, VF2), ``ursim_core.matching.auto_m`` (the automatic
choice of m, with the evidence for the defaults) and ``ursim_core.evaluation.kth_protocol`` (the KTH
evaluation protocol).

Segmentation for matching: the evidence was gathered with MAORIS preset ``"default"`` (t = 0.25,
doors 40; the parameters the KTH ground truth was clicked on) for both maps, binarised at > 250.
The ``"sketch"`` preset (:func:`~ursim_core.segmentation.segment`'s default, chosen for
segmentation quality; t = 0.30, doors 60 when this was measured) split the sketches more and
matched worse (paper T4, oracle m: 0.51 against 0.665 mean F1). :func:`~ursim_core.matching.match_maps`
segments two maps as the matcher expects before matching them.

Degenerate inputs (an empty graph, a single region, no unique region, no anchor, no seed,
disconnected graphs, constant attributes) never raise: the result is valid, possibly empty, and its
``reason`` says what was degenerate.
"""

from __future__ import annotations

import dataclasses
import functools

from ursim_core.errors import ParameterError
from ursim_core.matching.auto_m import choose_m, chosen_of, matched_sweep
from ursim_core.matching.config import M_GRID, MATCH_PRESETS, MATCHERS, PARTIAL_SKETCH, MatchConfig
from ursim_core.matching.constraints import CONSTRAINED_MATCHERS
from ursim_core.matching.laid import (
    LaidAhead,
    elastic_labels,
    laid_elastically,
    laying_answer,
    window_rule,
)
from ursim_core.matching.orientation import DOOR_EVIDENCE, broken_adjacencies, misplaced_doors
from ursim_core.matching.oriented import (
    candidate_overlaps,
    carried_by_orientation,
    nearest_orientations,
    orientations_to_try,
    prepare_oriented,
    region_graph_of,
    reoriented,
    sketch_outlines,
    window_reading,
)
from ursim_core.matching.overlay_answer import prepare_overlay
from ursim_core.matching.partial import PARTIAL_NOTE, looks_partial, reading_windows, window_starts_of
from ursim_core.matching.refit import refit_by_transform, refit_from, refit_positions, signature_start
from ursim_core.matching.resampling import voted_answer, with_resampled
from ursim_core.matching.results import MatchResult, Prepared, replaced, require_segmentations
from ursim_core.matching.single import match_at, pair_cost_matrix, seed_cap, seed_pairs

__all__ = [
    "MATCH_PRESETS",
    "M_GRID",
    "MATCHERS",
    "MatchConfig",
    "MatchResult",
    "Prepared",
    "prepare",
    "match_prepared",
    "match_at",
    "match",
    "seed_pairs",
    "seed_cap",
    "pair_cost_matrix",
]


def prepare(
    sketch_seg, metric_seg, config: MatchConfig = MatchConfig(), *, progress=None, constraints=None
) -> Prepared:
    """Compute everything that does not depend on m, the sketch's orientation included.

    A sketch segmented in several resamplings (``Segmentation.resampled``) has each of them
    prepared as well (``config.resampling_vote``, the planar matcher, no constraints), and
    :func:`match_prepared` votes over their answers (:mod:`ursim_core.matching.resampling`).

    With ``config.orientation='any'`` (the default) every candidate orientation of
    :func:`ursim_core.matching.orientation.orientation_candidates` is matched with the
    configured m (the automatic m by default) and the one whose answer scores lowest is kept;
    ties go to the earlier candidate, the identity first. With the automatic m the candidates
    are screened on every second m of the grid and the ``config.orientation_finalists`` best
    get the full sweep. The signatures are computed once:
    only the position term and the neighbour orders depend on the orientation. With
    ``config.position_refits`` (the planar matcher), the answer in each orientation is matched
    again with the sketch's positions laid on the metric map by its own pairs
    (:mod:`ursim_core.matching.refit`), and with ``config.signature_refit`` also laid by the answer
    matched without the position term; the orientations are ranked by the refitted answers, and
    the answer found (the refitted one, or with ``config.keep_refit=False`` the one before the
    refit) is kept in ``Prepared.chosen``. With ``config.auto_partial``, a sketch laid in the part of
    the metric map it resembles (the window laying) is prepared again with
    :data:`~ursim_core.matching.config.PARTIAL_SKETCH`'s options (:mod:`ursim_core.matching.partial`).
    ``config.matcher='auto'`` is resolved first (:meth:`MatchConfig.resolved`).

    Parameters
    ----------
    sketch_seg, metric_seg : Segmentation or networkx.Graph
        Segmentations (their ``.graph`` is used) or region graphs directly.
    config : MatchConfig
    progress : callable, optional
        ``progress(fraction, message)`` while the orientations are tried.
    constraints : MatchConstraints, optional
        Pairs every answer contains or avoids, regions it leaves alone
        (:mod:`ursim_core.matching.constraints`): the planar and Hungarian matchers honour them
        in every orientation and at every m, so a person's pairs also steer the orientation; two
        fixed pairs or more lay the map for the overlay matcher.

    Raises
    ------
    ParameterError
        ``constraints`` name a region the segmentations do not have, or the matcher cannot
        take them (VF2).

    Examples
    --------
    >>> import networkx as nx
    >>> g = nx.path_graph(3)
    >>> nx.set_node_attributes(g, {0: 50, 1: 10, 2: 12}, "size")
    >>> nx.set_node_attributes(g, 0.3, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (0, 20)}, "centroid")
    >>> prepare(g, g.copy()).c_matrix.shape
    (3, 3)
    """
    require_segmentations(sketch_seg, metric_seg)
    prepared = _prepare_one(sketch_seg, metric_seg, config, progress=progress, constraints=constraints)
    labels = elastic_labels(prepared, sketch_seg, metric_seg, largest=_SCREEN_BY_ASSIGNMENT)
    answers: dict = {}
    if labels is not None and getattr(sketch_seg, "resampled", ()) and prepared.config.resampling_vote:
        # The first segmentation's reading is nearly always the voted one: its sketch is laid on
        # a thread (OpenCV's flow releases the GIL) while the other segmentations are prepared.
        # A turned KTH pair 51.8-58.9 -> 42.1-45.7 ms (interleaved x3); with nothing to prepare
        # meanwhile the thread would only add its start.
        answer = laying_answer(prepared, prepared.orientation)
        answers[prepared.orientation] = LaidAhead(
            *labels, prepared.orientation, prepared.config.overlay_min_iou, answer, window=window_rule(prepared.config)
        )
    prepared = with_resampled(prepared, sketch_seg, metric_seg, _prepare_one)
    if labels is not None:
        prepared = dataclasses.replace(
            prepared, sketch_labels=labels[0], metric_labels=labels[1], elastic_answers=answers
        )
        if looks_partial(prepared):
            partial = config.replace(**PARTIAL_SKETCH)
            again = prepare(sketch_seg, metric_seg, partial, progress=progress, constraints=constraints)
            return dataclasses.replace(again, notes=(*again.notes, PARTIAL_NOTE))
    return prepared


def _prepare_one(
    sketch_seg,
    metric_seg,
    config: MatchConfig,
    *,
    progress=None,
    constraints=None,
    orientations=None,
    overlaps=None,
    windows=None,
    window_starts=None,
) -> Prepared:
    """:func:`prepare` of one segmentation of the sketch; with ``orientations``, only the
    candidates nearest to them are tried (:func:`~ursim_core.matching.oriented.nearest_orientations`);
    with ``overlaps`` and ``windows`` (another segmentation's ``Prepared.orientation_overlaps``
    and ``orientation_windows``), each candidate takes the free-space overlap and the best window
    of the nearest orientation measured there (:func:`~ursim_core.matching.oriented.carried_by_orientation`)
    instead of being fitted again; so do ``window_starts`` (``Prepared.orientation_window_starts``)."""
    config = config.resolved()
    sketch_graph, metric_graph = region_graph_of(sketch_seg), region_graph_of(metric_seg)
    constraints = constraints or None
    if constraints is not None:
        constraints.check_regions(sketch_graph.nodes, metric_graph.nodes)
        if config.matcher not in CONSTRAINED_MATCHERS:
            raise ParameterError(
                f"constraints (fixed, forbidden or excluded regions) need the planar, Hungarian or overlay "
                f"matcher, not {config.matcher!r}",
                field="constraints",
            )
    if config.matcher == "overlay":
        return prepare_overlay(sketch_seg, metric_seg, config, constraints)
    if orientations and config.vote_orientations == "first":
        # Another segmentation of a resampled sketch, in the first one's finalists as they are:
        # its own wall angle is not measured (MatchConfig.vote_orientations).
        candidates = list(orientations)
    else:
        candidates = orientations_to_try(config, sketch_seg, metric_seg)
        if orientations:
            candidates = nearest_orientations(candidates, orientations)
    outlines = sketch_outlines(sketch_seg, sketch_graph, candidates)
    base = prepare_oriented(sketch_graph, metric_graph, config, candidates[0], outlines)
    if constraints is not None:
        base = dataclasses.replace(base, constraints=constraints)
    if len(candidates) == 1:
        if not _refits(config) or not config.keep_refit:
            return base  # without keep_refit the refit only ranks orientations, and there is one
        base, result = _refitted(base, match_prepared(base, progress=progress))
        return dataclasses.replace(base, chosen=result)

    def candidate(index: int) -> Prepared:
        return base if index == 0 else reoriented(base, sketch_graph, candidates[index], outlines)

    if max(base.c_matrix.shape) > _SCREEN_BY_ASSIGNMENT:
        # Large graphs: one planar sweep costs seconds, so the orientation is chosen by how well
        # every region finds a close partner (mean of the row and column minima of c: all
        # regions vote, and positions dominate c there). O(n1 n2), no matching. The candidates
        # are made one at a time and only the best is kept (each c is n1 x n2 floats).
        def partner_cost(prepared: Prepared) -> float:
            c_matrix = prepared.c_matrix
            return float(c_matrix.min(axis=1).mean() + c_matrix.min(axis=0).mean())

        best: tuple[float, int, Prepared] | None = None
        for index in range(len(candidates)):
            prepared = candidate(index)
            cost = partner_cost(prepared)
            if best is None or (cost, index) < best[:2]:
                best = (cost, index, prepared)
            del prepared
        prepared_candidates = {best[1]: best[2]}
        finalists = [best[1]]
    else:
        prepared_candidates = {index: candidate(index) for index in range(len(candidates))}
        finalists = range(len(candidates))
    if len(finalists) < 2:
        overlaps = {}
    else:
        # Another segmentation of the sketch in the same frame measured them already: its free
        # space differs from this one's by resampling noise (see resampling.with_resampled).
        overlaps = carried_by_orientation(overlaps, candidates, finalists) if overlaps else None
        if overlaps is None:
            overlaps = candidate_overlaps(config, sketch_seg, metric_seg, candidates, list(finalists))

    def ranked(cost: float, index: int) -> float:
        # The hypothesis score divided by the free-space overlap in that orientation: both must
        # agree (see ursim_core.matching.alignment). A ratio is scale-free: no weight to tune.
        return cost / overlaps[index] ** config.orientation_overlap if overlaps else cost

    known: dict[int, dict] = {}  # per candidate: the results of its screening, by m
    if (
        len(finalists) > 1
        and config.m == "auto"
        and len(candidates) > config.orientation_finalists
        and len(config.m_grid) > 2 * _COARSE_STEP
    ):
        # Screen every orientation on a coarse m grid first; only the best few get the full sweep.
        coarse = config.replace(m_grid=tuple(config.m_grid[_COARSE_STEP // 2 :: _COARSE_STEP]))
        screened = []
        for index, prepared in prepared_candidates.items():
            coarse_prepared = dataclasses.replace(prepared, config=coarse)
            results, known[index] = matched_sweep(coarse_prepared)
            screened.append((ranked(chosen_of(coarse_prepared, results).normalised_cost, index), index))
        finalists = sorted(index for _, index in sorted(screened)[: config.orientation_finalists])
    trials = []
    doors: list[float] = []  # per trial, with a door penalty: misplaced_doors of its answer
    starts: dict = {}  # the signature starts of the refit, by mirror flag (see _refitted)
    # The windows are searched once (per finalist) for the refit's starts and the reading.
    laid_starts, searched = window_starts_of(
        config,
        sketch_seg,
        metric_seg,
        candidates,
        prepared_candidates,
        finalists,
        window_starts,
        refits=bool(_refits(config)),
        largest=_SCREEN_BY_ASSIGNMENT,
    )
    for step, index in enumerate(finalists):
        prepared = prepared_candidates[index]
        share = _share_of(progress, step, len(finalists))
        if config.m == "auto":
            # The full sweep of a screened orientation: half its values of m are matched already.
            result = choose_m(prepared, progress=share, known=known.get(index))
        else:
            result = match_prepared(prepared, progress=share)
        refitted, answer = _refitted(prepared, result, starts, laid_starts.get(index))
        # Ranked by the refitted answer's score either way; keep_refit=False keeps the first answer.
        kept = (refitted, answer) if config.keep_refit else (prepared, result)
        cost = answer.normalised_cost
        if config.adjacency_penalty:
            # A reading that joins rooms that are not neighbours ranks worse (round 44).
            broken = broken_adjacencies(answer.pairs, prepared.sketch_graph, prepared.metric_graph)
            cost *= 1.0 + config.adjacency_penalty * broken
        trials.append([ranked(cost, index), index, *kept])
        if config.door_penalty:
            doors.append(misplaced_doors(answer.pairs, prepared.sketch_graph, prepared.metric_graph))
    if doors and min(doors) < DOOR_EVIDENCE:
        # A reading whose rooms touch their neighbours elsewhere than on the map ranks worse too
        # (round 46), when some reading puts the sketch's doors where the map has them: where none
        # does, the doors were not drawn where they are, and say nothing of the reading.
        for trial, misplaced in zip(trials, doors):
            trial[0] *= 1.0 + config.door_penalty * misplaced
    found: dict = {}
    if config.window_reading_margin and len(trials) > 1 and window_rule(config) != "off":
        found = reading_windows(
            base,
            sketch_seg,
            metric_seg,
            candidates,
            [trial[1] for trial in trials],
            windows,
            searched,
            largest=_SCREEN_BY_ASSIGNMENT,
        )
    taken = None
    if found:
        # A partial sketch can rank better read wrongly; read rightly it resembles a part of the
        # map clearly better than read so (round 48).
        ranked_best = min(trials, key=lambda trial: (trial[0], trial[1]))[1]
        taken = window_reading(found, ranked_best, margin=config.window_reading_margin)
    _, _, prepared, result = min(trials, key=lambda trial: (trial[1] != taken, trial[0], trial[1]))
    scan = {candidates[trial[1]]: float(trial[0]) for trial in trials}
    return dataclasses.replace(
        prepared,
        orientation_scan=scan,
        chosen=replaced(result, orientation_scan=scan),
        orientation_overlaps={candidates[index]: value for index, value in overlaps.items()},
        orientation_windows={candidates[index]: value for index, value in found.items()},
        orientation_window_starts={candidates[index]: value for index, value in laid_starts.items()},
    )


def _refits(config: MatchConfig) -> int:
    """How many position refits apply (:mod:`ursim_core.matching.refit`): planar, with positions."""
    return config.position_refits if config.matcher == "planar" and config.position_weight else 0


def _refitted(
    prepared: Prepared, result: MatchResult, starts: dict | None = None, window_start=None
) -> tuple[Prepared, MatchResult]:
    """The answer after the position refits (:mod:`ursim_core.matching.refit`), or as given.

    With ``signature_refit``, the sketch is also laid on the metric map by the pairs of the answer
    matched without the position term, a start that does not depend on the sketch covering the
    metric map in proportion. That answer depends on the orientation only through the mirror
    (a turn keeps every neighbour order), so ``starts`` keeps it per mirror flag for the other
    orientations of the same pair.
    """
    if max(prepared.c_matrix.shape) > _SCREEN_BY_ASSIGNMENT:
        # Sketch-sized graphs only, where it was measured: two generated 1000-region buildings
        # took 83 s to prepare with it against 2.8 s without (`ursim bench scale`, 4000 px).
        return prepared, result
    first, first_answer = prepared, result
    for _ in range(_refits(prepared.config)):
        refitted, answer = refit_positions(prepared, result, _match_coarsely)
        if answer is result:
            break
        prepared, result = refitted, answer
    if _refits(first.config) and first.config.signature_refit:
        starts = {} if starts is None else starts
        mirrored = bool(first.orientation[1])
        if mirrored not in starts:
            starts[mirrored] = signature_start(first, _match_sparsely)
        start = starts[mirrored]
        if start is not None and set(start.pairs) != set(first_answer.pairs):
            refitted = refit_from(first, start.pairs, _match_coarsely)
            if refitted is not None and refitted[1].normalised_cost < result.normalised_cost:
                prepared, result = refitted
    if window_start is not None:
        # Laid in the window its free space resembles (MatchConfig.window_start), refitted by its
        # own pairs as the first answer is, and kept when its score is lower (round 50).
        laid = refit_by_transform(first, window_start, _match_coarsely)
        if laid is not None:
            laid = refit_positions(*laid, _match_coarsely)
            if laid[1].normalised_cost < result.normalised_cost:
                prepared, result = laid
    return prepared, result


def _match_sparsely(prepared: Prepared) -> MatchResult:
    """:func:`_match_coarsely` over every second m of its grid (every fourth of the full grid)."""
    config = prepared.config
    if config.m == "auto" and len(config.m_grid) > 4 * _COARSE_STEP:
        sparse = config.replace(m_grid=tuple(config.m_grid[_COARSE_STEP // 2 :: 2 * _COARSE_STEP]))
        return replaced(match_prepared(dataclasses.replace(prepared, config=sparse)), config=config)
    return _match_coarsely(prepared)


def _match_coarsely(prepared: Prepared) -> MatchResult:
    """The answer at the configured m; the automatic m over every ``_COARSE_STEP``-th m of the
    grid, as the orientations are screened. For the refit: on the 18 KTH sketches in 8
    orientations and on ``ursim bench invariance`` it gave the same answers as the full grid, and
    it took prepare from 54 to 51 ms median per KTH pair (interleaved A/B, quiet machine)."""
    config = prepared.config
    if config.m == "auto" and len(config.m_grid) > 2 * _COARSE_STEP:
        coarse = config.replace(m_grid=tuple(config.m_grid[_COARSE_STEP // 2 :: _COARSE_STEP]))
        answer = match_prepared(dataclasses.replace(prepared, config=coarse))
        return replaced(answer, config=config)  # the result records the caller's options
    return match_prepared(prepared)


#: With the automatic m, orientations are screened at every ``_COARSE_STEP``-th m of the grid and
#: the ``MatchConfig.orientation_finalists`` best get the full sweep (and the position refit, see
#: :func:`prepare`). Round 6 (tuned on the 18 KTH sketches, interleaved A/B in one session): step 2
#: with 2 finalists gave the same F1 in every orientation as the full sweep of all 8 (0.651
#: overall) at 36 ms median per pair, against 58 ms with 3 finalists. Round 8, with exact
#: quarter-turn candidates and the refit: 2 and 3 finalists gave the same on KTH but 2 cut the
#: right reading of a nearly symmetric generated plan; round 36: 4 (see the option).
_COARSE_STEP = 2
#: Above this many regions in either map, orientations are screened by assignment cost instead,
#: and the answer is not refitted.
_SCREEN_BY_ASSIGNMENT = 60


def _share_of(progress, index: int, count: int):
    """``progress`` for step ``index`` of ``count``: fractions scaled into its share, messages prefixed."""
    if progress is None:
        return None

    def report(fraction: float, message: str) -> None:
        progress((index + fraction) / count, f"orientation {index + 1} of {count}: {message}")

    return report


def match_prepared(prepared: Prepared, m: float | None = None, *, progress=None) -> MatchResult:
    """Run the configured matcher at one m (or the automatic m when ``m`` is None and
    the config says ``'auto'``).

    ``progress(fraction, message)``, when given, follows the automatic m's sweep.

    Examples
    --------
    >>> import networkx as nx
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> sorted(match_prepared(prepare(g, g.copy()), 0.01).pairs)
    [(0, 0), (1, 1), (2, 2), (3, 3)]
    """
    if prepared.resampled is not None:
        result = voted_answer(prepared, m, functools.partial(_match_one, progress=progress))
    else:
        result = _match_one(prepared, m, progress=progress)
    if PARTIAL_NOTE in prepared.notes and PARTIAL_NOTE not in result.reason:
        # The answers found while the orientation was chosen came before the note (auto_partial).
        result = replaced(result, reason="; ".join(filter(None, (result.reason, PARTIAL_NOTE))))
    if prepared.sketch_labels is None:
        return result
    return laid_elastically(prepared, result)


def _match_one(prepared: Prepared, m: float | None = None, *, progress=None) -> MatchResult:
    """:func:`match_prepared` of one segmentation of the sketch."""
    config = prepared.config
    if config.matcher == "overlay" and prepared.chosen is not None:
        # Its answer does not depend on m: the same at every m of a sweep.
        return dataclasses.replace(prepared.chosen, m=float(m) if m is not None else prepared.chosen.m)
    if m is None and prepared.chosen is not None:
        return prepared.chosen
    if m is None:
        if config.m == "auto":
            return choose_m(prepared, progress=progress)
        m = float(config.m)
    return match_at(prepared, m)


def match(
    sketch_seg, metric_seg, *, config: MatchConfig = MatchConfig(), progress=None, constraints=None
) -> MatchResult:
    """Match the regions of a sketch to the regions of a metric map.

    Parameters
    ----------
    sketch_seg, metric_seg : Segmentation or networkx.Graph
    config : MatchConfig
    progress : callable, optional
        ``progress(fraction, message)`` during the automatic m's sweep.
    constraints : MatchConstraints, optional
        Pairs the answer must contain or avoid (see :func:`prepare`).

    Returns
    -------
    MatchResult

    Examples
    --------
    >>> import networkx as nx
    >>> g = nx.cycle_graph(4)
    >>> nx.set_node_attributes(g, {0: 90, 1: 10, 2: 20, 3: 30}, "size")
    >>> nx.set_node_attributes(g, {0: 0.1, 1: 0.5, 2: 0.3, 3: 0.2}, "pca_shape")
    >>> nx.set_node_attributes(g, {0: (0, 0), 1: (0, 10), 2: (10, 10), 3: (10, 0)}, "centroid")
    >>> result = match(g, g.copy())
    >>> sorted(result.pairs), result.reason
    ([(0, 0), (1, 1), (2, 2), (3, 3)], '')
    """
    prepared = prepare(sketch_seg, metric_seg, config, progress=progress, constraints=constraints)
    return match_prepared(prepared, progress=progress)
