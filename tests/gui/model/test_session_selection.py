"""The selection of a session (ursim_gui.model.session_selection): rules, focus and signals."""

from __future__ import annotations

import pytest
from conftest import Recorder


def test_selection_rules_and_signals(session):
    clique_id = session.link([1, 2], [5])
    recorder = Recorder(session)
    session.select_clique(clique_id)
    assert session.selection == {"sketch": frozenset({1, 2}), "metric": frozenset({5})}
    session.select("sketch", [4], add=True)  # extend the clique's selection, keep the clique
    assert session.selected_clique == clique_id and session.selection["sketch"] == frozenset({1, 2, 4})
    session.select("metric", [6])  # a plain click starts a new selection
    assert session.selected_clique is None and session.selection["metric"] == frozenset({6})
    session.select("metric", [6])  # unchanged: no signal
    session.clear_selection()
    session.clear_selection()
    assert session.selection == {"sketch": frozenset(), "metric": frozenset()}
    assert recorder.count("selection_changed") == 4
    with pytest.raises(KeyError):
        session.select_clique(99)


def test_a_plain_selection_after_a_clique_clears_the_cliques_other_side(session):
    clique_id = session.link([1], [5])
    session.select_clique(clique_id, focus=("metric", 5))
    assert session.focus == ("metric", 5)
    session.select("sketch", [2])
    # The metric region was the clique's, not picked: linking now must not pull it in.
    assert session.selection == {"sketch": frozenset({2}), "metric": frozenset()}
    assert session.selected_clique is None and session.focus == ("sketch", 2)


def test_the_focus_is_the_one_region_picked_by_itself(session):
    session.select("sketch", [1, 2])
    assert session.focus is None
    session.select("sketch", [3], add=True)
    assert session.focus == ("sketch", 3)
    session.select("metric", [5, 6], add=True)  # several at once: the focus stays
    assert session.focus == ("sketch", 3)
    session.clear_selection()
    assert session.focus is None


def test_deselecting_a_clique_or_deleting_it_clears_it_once(session):
    clique_id = session.link([1], [5])
    recorder = Recorder(session)
    session.select_clique(clique_id)
    session.select_clique(None)
    session.select_clique(None)  # nothing selected already: no signal
    assert session.selected_clique is None and recorder.count("selection_changed") == 2
    session.select_clique(clique_id)
    session.delete_clique(clique_id)
    assert session.selected_clique is None and session.focus is None
    assert recorder.count("selection_changed") == 4
