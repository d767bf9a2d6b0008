"""A tiny, Qt-free signal: the model's way of telling views that something changed.

The model layer must import without PySide6, so it cannot use ``QtCore.Signal``.
Views connect their slots to these signals; the Qt layer is free to re-emit them
as Qt signals or to call widgets directly, since everything runs in the GUI thread.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["Signal"]


class Signal:
    """A list of callables that :meth:`emit` calls in connection order.

    Parameters
    ----------
    name : str, optional
        Shown by ``repr`` to make debugging output readable.

    Notes
    -----
    - Slots are held by strong reference; a view disconnects when it is closed.
    - Connecting the same slot twice makes it run twice per emit (as Qt does
      without ``UniqueConnection``).
    - An exception raised by a slot propagates out of :meth:`emit` at once and the
      remaining slots are not called. Slots are view code; a failing slot is a bug
      that must reach the application's excepthook rather than be swallowed.
    - Slots connected or disconnected while an emit is running take effect from
      the next emit (emit iterates over a snapshot).

    Examples
    --------
    >>> changed = Signal("changed")
    >>> seen = []
    >>> changed.connect(seen.append)
    >>> changed.emit(3)
    >>> seen
    [3]
    >>> changed.disconnect(seen.append)
    >>> changed.emit(4)
    >>> seen
    [3]
    """

    __slots__ = ("_slots", "name")

    def __init__(self, name: str = "") -> None:
        self.name = name
        self._slots: list[Callable[..., Any]] = []

    def connect(self, slot: Callable[..., Any]) -> None:
        """Call ``slot(*args)`` on every later :meth:`emit`.

        Raises
        ------
        TypeError
            When ``slot`` is not callable (caught at connect time, not at the
            first emit far from the mistake).
        """
        if not callable(slot):
            raise TypeError(f"cannot connect a non-callable {slot!r} to signal {self.name or '<unnamed>'}")
        self._slots.append(slot)

    def disconnect(self, slot: Callable[..., Any]) -> None:
        """Remove one connection of ``slot`` (the earliest one).

        Raises
        ------
        ValueError
            When ``slot`` is not connected.
        """
        # Bound methods compare equal when they wrap the same function and object,
        # so ``disconnect(view.refresh)`` finds the ``connect(view.refresh)`` entry.
        try:
            self._slots.remove(slot)
        except ValueError:
            raise ValueError(f"{slot!r} is not connected to signal {self.name or '<unnamed>'}") from None

    def emit(self, *args: Any) -> None:
        """Call every connected slot with ``args``, in connection order."""
        for slot in tuple(self._slots):
            slot(*args)

    @property
    def n_connections(self) -> int:
        """Number of connected slots (a slot connected twice counts twice)."""
        return len(self._slots)

    def __repr__(self) -> str:
        return f"Signal({self.name!r}, {len(self._slots)} slot(s))"
