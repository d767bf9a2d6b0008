"""Undo/redo stack: values, texts, redo tail, the changed signal, map_values."""

import pytest

from ursim_gui.model.history import History


def make_history(*steps):
    history = History()
    value = ""
    for step in steps:
        new_value = value + step
        # The next entry's ``before`` is this entry's ``after`` object, as in the session.
        history.push(f"add {step}", value, new_value)
        value = new_value
    return history


def test_undo_returns_before_values_and_redo_after_values():
    history = make_history("a", "b", "c")
    assert history.undo() == "ab"
    assert history.undo() == "a"
    assert history.redo() == "ab"
    assert history.redo() == "abc"
    assert history.index == 3 and len(history) == 3


def test_can_flags_and_texts_follow_the_position():
    history = History()
    assert (history.can_undo, history.can_redo, history.undo_text, history.redo_text) == (False, False, "", "")
    history.push("link 1-2", "x", "y")
    assert (history.can_undo, history.can_redo, history.undo_text, history.redo_text) == (True, False, "link 1-2", "")
    history.undo()
    assert (history.can_undo, history.can_redo, history.undo_text, history.redo_text) == (False, True, "", "link 1-2")


def test_undo_and_redo_past_the_ends_raise():
    history = make_history("a")
    with pytest.raises(IndexError, match="redo"):
        history.redo()
    history.undo()
    with pytest.raises(IndexError, match="undo"):
        history.undo()


def test_push_after_undo_drops_the_redo_tail():
    history = make_history("a", "b", "c")
    history.undo()
    history.undo()
    history.push("add x", "a", "ax")
    assert not history.can_redo
    assert [entry.description for entry in history.entries()] == ["add a", "add x"]
    assert history.undo() == "a"
    assert history.undo() == ""


def test_history_is_unlimited():
    history = make_history(*["s"] * 5000)
    for _ in range(5000):
        history.undo()
    assert not history.can_undo
    assert history.redo_text == "add s"


def test_clear_forgets_everything():
    history = make_history("a", "b")
    history.undo()
    history.clear()
    assert (history.can_undo, history.can_redo, len(history)) == (False, False, 0)


def test_changed_is_emitted_once_per_mutation():
    history = History()
    count = []
    history.changed.connect(lambda: count.append(1))
    history.push("a", 0, 1)
    history.push("b", 1, 2)
    history.undo()
    history.redo()
    history.map_values(lambda v: v)
    history.clear()
    assert len(count) == 6


def test_map_values_rewrites_every_value_once_per_object():
    history = make_history("a", "b", "c")
    calls = []

    def shout(value):
        calls.append(value)
        return value.upper()

    history.undo()
    history.map_values(shout)
    # 4 distinct values: "", "a", "ab", "abc" (entry boundaries are shared objects).
    assert sorted(calls) == ["", "a", "ab", "abc"]
    assert history.redo() == "ABC"
    assert [history.undo() for _ in range(3)] == ["AB", "A", ""]
