"""A simulated review: how many edits an annotator needs to turn the matcher's answer into theirs.

Every automatic clique an annotator does not have to fix is time saved. An annotator who reviews
an answer rejects the wrong pairs, links the places the matcher missed and accepts the rest; with
:mod:`ursim_core.matching.constraints` the matcher can be run again on that review, keeping what
was said and building on it. :func:`simulate_review` counts the edits (a rejection or a link; an
acceptance is the reading the review needs anyway and is not counted) until no pair of the
answer is wrong and no reference clique is missed, in three workflows:

- ``"by hand"``: the answer is never matched again; every wrong pair is rejected and every missed
  clique linked.
- ``"links first"``: the largest missed clique (by its largest sketch region) is linked and the
  pair matched again with the review so far, until nothing is missed; then the pairs still wrong
  are rejected.
- ``"every edit"``: the largest wrong pair is rejected, or when none is left the largest missed
  clique linked, and the pair is matched again after each edit.

A pair is wrong when no reference clique holds both its regions; a clique is missed when no pair
of the answer and no link lies inside it. The reference cliques are region sets of the matcher's
segmentations (:func:`ursim_core.evaluation.kth_protocol.reference_cliques`).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["WORKFLOWS", "ReviewOutcome", "simulate_review"]

WORKFLOWS = ("by hand", "links first", "every edit")

#: Matching rounds at most per review (every round adds a constraint, so this is never reached on
#: sketch-sized maps; it bounds a pathological case).
MAX_ROUNDS = 50


@dataclass(frozen=True)
class ReviewOutcome:
    """Edits of one simulated review: ``rejections`` + ``links``, and the matching ``rounds`` run."""

    workflow: str
    rejections: int
    links: int
    rounds: int
    finished: bool

    @property
    def edits(self) -> int:
        return self.rejections + self.links


def _inside(pair, clique) -> bool:
    return pair[0] in clique[0] and pair[1] in clique[1]


def simulate_review(sketch_seg, metric_seg, reference, *, workflow: str = "links first", config=None) -> ReviewOutcome:
    """Simulate an annotator reviewing the matcher's answer of a pair (see the module docstring).

    Parameters
    ----------
    sketch_seg, metric_seg : Segmentation
    reference : list of (set, set)
        The annotator's cliques as (sketch regions, metric regions); cliques with an empty side are
        ignored.
    workflow : {'by hand', 'links first', 'every edit'}
    config : MatchConfig, optional

    Returns
    -------
    ReviewOutcome
    """
    from ursim_core.correspondences import Clique
    from ursim_core.errors import ParameterError
    from ursim_core.matching import MatchConfig, constraints_from_cliques, match

    if workflow not in WORKFLOWS:
        raise ParameterError(f"must be one of {WORKFLOWS}, not {workflow!r}", field="workflow")
    config = config or MatchConfig()
    reference = [(set(s), set(m)) for s, m in reference if s and m]
    sketch_sizes = dict(sketch_seg.graph.nodes(data="size", default=0))
    sizes = {"sketch": sketch_sizes, "metric": dict(metric_seg.graph.nodes(data="size", default=0))}
    review: list = []  # the person's cliques: rejections and links
    links: list = []

    def state(pairs):
        wrong = [pair for pair in pairs if not any(_inside(pair, clique) for clique in reference)]
        missed = [
            clique
            for clique in reference
            if not any(_inside(pair, clique) for pair in pairs)
            and not any(link[0] <= clique[0] and link[1] <= clique[1] for link in links)
        ]
        return wrong, missed

    def matched_again(pairs, wrong):
        # The review so far, with every pair of the answer that is not wrong accepted.
        accepted = [
            Clique(id=10_000 + k, sketch_regions=(a,), metric_regions=(b,), source="auto", status="accepted")
            for k, (a, b) in enumerate(pair for pair in pairs if pair not in wrong)
        ]
        constraints = constraints_from_cliques([*review, *accepted], sizes=sizes) or None
        return list(match(sketch_seg, metric_seg, config=config, constraints=constraints).pairs)

    pairs = list(match(sketch_seg, metric_seg, config=config).pairs)
    rounds, rejections, n_links = 1, 0, 0
    wrong, missed = state(pairs)
    if workflow == "by hand":
        return ReviewOutcome(workflow, len(wrong), len(missed), rounds, True)
    while (wrong or missed) and rounds <= MAX_ROUNDS:
        if workflow == "links first" and not missed:
            return ReviewOutcome(workflow, rejections + len(wrong), n_links, rounds, True)
        if wrong and workflow == "every edit":
            a, b = max(wrong, key=lambda pair: (sketch_sizes.get(pair[0], 0), pair))
            review.append(
                Clique(id=len(review) + 1, sketch_regions=(a,), metric_regions=(b,), source="auto", status="rejected")
            )
            rejections += 1
        else:
            clique = max(missed, key=lambda c: (max(sketch_sizes.get(r, 0) for r in c[0]), sorted(c[0])))
            links.append(clique)
            review.append(
                Clique(
                    id=len(review) + 1, sketch_regions=tuple(sorted(clique[0])), metric_regions=tuple(sorted(clique[1]))
                )
            )
            n_links += 1
        pairs = matched_again(pairs, wrong)
        rounds += 1
        wrong, missed = state(pairs)
    return ReviewOutcome(workflow, rejections, n_links, rounds, not (wrong or missed))
