"""The Qt-free Signal: order, disconnect, exceptions, re-entrancy."""

import pytest

from ursim_gui.model.signals import Signal


def test_slots_run_in_connection_order_with_the_emitted_arguments():
    signal = Signal("s")
    calls = []
    signal.connect(lambda *args: calls.append(("first", args)))
    signal.connect(lambda *args: calls.append(("second", args)))
    signal.emit(1, "two")
    assert calls == [("first", (1, "two")), ("second", (1, "two"))]


def test_emit_without_slots_does_nothing():
    Signal().emit("ignored")


def test_disconnect_stops_calls_and_only_removes_one_connection():
    signal = Signal()
    calls = []
    signal.connect(calls.append)
    signal.connect(calls.append)
    signal.emit(1)
    signal.disconnect(calls.append)
    signal.emit(2)
    signal.disconnect(calls.append)
    signal.emit(3)
    assert calls == [1, 1, 2]
    assert signal.n_connections == 0


def test_bound_methods_disconnect_by_equality():
    class View:
        def __init__(self):
            self.seen = 0

        def refresh(self):
            self.seen += 1

    view = View()
    signal = Signal()
    signal.connect(view.refresh)
    signal.emit()
    signal.disconnect(view.refresh)  # a fresh bound-method object, equal to the connected one
    signal.emit()
    assert view.seen == 1


def test_disconnecting_an_unknown_slot_raises():
    with pytest.raises(ValueError, match="not connected"):
        Signal("named").disconnect(print)


def test_connecting_a_non_callable_raises():
    with pytest.raises(TypeError):
        Signal().connect(42)


def test_a_raising_slot_propagates_and_stops_later_slots():
    signal = Signal()
    calls = []

    def broken():
        raise RuntimeError("boom")

    signal.connect(lambda: calls.append("before"))
    signal.connect(broken)
    signal.connect(lambda: calls.append("after"))
    with pytest.raises(RuntimeError, match="boom"):
        signal.emit()
    assert calls == ["before"]


def test_changes_during_emit_apply_from_the_next_emit():
    signal = Signal()
    calls = []

    def late():
        calls.append("late")

    def connect_late_and_leave():
        calls.append("first")
        signal.connect(late)
        signal.disconnect(connect_late_and_leave)

    signal.connect(connect_late_and_leave)
    signal.emit()
    assert calls == ["first"]
    signal.emit()
    assert calls == ["first", "late"]
