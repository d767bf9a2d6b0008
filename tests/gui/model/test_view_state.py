"""What the views draw from the session's state (ursim_gui.model.view_state): side colours, connector ends, badges."""

from __future__ import annotations

import numpy as np
from conftest import three_room_labels

from ursim_core.correspondences import Clique, Correspondences
from ursim_gui.model.region_style import (
    NEUTRAL_REGION,
    clique_colour,
    palette_colour,
)
from ursim_gui.model.view_state import eval_badges, first_regions, side_colour_table


def _corr():
    return Correspondences(
        cliques=(
            Clique(id=1, sketch_regions=(1,), metric_regions=(3,), source="auto"),
            Clique(id=2, sketch_regions=(2,), metric_regions=(2,), status="rejected"),
        )
    )


def test_side_colours_follow_cliques_and_match_across_views():
    labels = three_room_labels()
    corr = _corr()
    sketch = side_colour_table(corr, "sketch", labels, clique_colour)
    metric = side_colour_table(corr, "metric", labels, clique_colour)
    assert tuple(sketch[1, :3]) == clique_colour(1) == tuple(metric[3, :3])
    assert tuple(sketch[2, :3]) == NEUTRAL_REGION  # rejected clique is not coloured
    assert tuple(metric[1, :3]) == NEUTRAL_REGION
    plain = side_colour_table(Correspondences(), "sketch", labels, clique_colour)
    assert tuple(plain[1, :3]) == palette_colour(1)


def test_connector_ends_and_badges():
    corr = Correspondences(cliques=(*_corr().cliques, Clique(id=3, sketch_regions=(3,))))
    assert first_regions(corr) == [(1, 1, 3)]  # rejected and one-sided cliques: no line
    marks = {1: "tp", 2: "fp"}
    assert eval_badges(corr, "sketch", marks.get) == {1: "TP", 2: "FP"}
    assert eval_badges(corr, "metric", marks.get) == {3: "TP", 2: "FP"}


def test_the_laid_sketch_is_made_only_for_a_laid_answer():
    from types import SimpleNamespace

    from ursim_gui.model.view_state import laid_sketch_of

    labels = three_room_labels()
    laid = SimpleNamespace(laid=True, orientation=(0.0, False))
    made = laid_sketch_of(laid, labels, labels)
    assert made.shape == labels.shape and set(np.unique(made)) <= set(np.unique(labels))
    # The same map laid on itself: each room lands on itself, but for its rim.
    for region in (1, 2, 3):
        assert np.count_nonzero((made == region) & (labels == region)) > 0.8 * np.count_nonzero(labels == region)
    assert laid_sketch_of(SimpleNamespace(laid=False, orientation=(0.0, False)), labels, labels) is None
    assert laid_sketch_of(laid, None, labels) is None and laid_sketch_of(None, labels, labels) is None
