"""Undo/redo as a stack of (description, before, after) values.

The session stores whole immutable ``Correspondences`` values rather than
commands, so undoing is "go back to that value" and can never drift from what
the user saw: there is no inverse operation to get wrong.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Generic, TypeVar

from ursim_gui.model.signals import Signal

__all__ = ["History", "HistoryEntry"]

T = TypeVar("T")


@dataclass(frozen=True)
class HistoryEntry(Generic[T]):
    """One undoable step: the value before it, the value after it, and its name."""

    description: str
    before: T
    after: T


class History(Generic[T]):
    """Unlimited linear undo/redo history.

    Entries ``[0, index)`` can be undone, entries ``[index, len)`` redone.
    Pushing a new entry after some undos drops the redo tail, as every editor does.

    Attributes
    ----------
    changed : Signal
        Emitted (no arguments) whenever ``can_undo``, ``can_redo`` or the texts
        may have changed: after push, undo, redo, clear and :meth:`map_values`.

    Examples
    --------
    >>> history = History()
    >>> history.push("add b", "a", "ab")
    >>> history.push("add c", "ab", "abc")
    >>> history.undo_text, history.undo()
    ('add c', 'ab')
    >>> history.redo()
    'abc'
    >>> history.undo(); history.undo()
    'ab'
    'a'
    >>> history.can_undo, history.redo_text
    (False, 'add b')
    """

    def __init__(self) -> None:
        self._entries: list[HistoryEntry[T]] = []
        self._index = 0
        self.changed = Signal("history.changed")

    def push(self, description: str, before: T, after: T) -> None:
        """Record a step that has already been applied (the current value is ``after``)."""
        del self._entries[self._index :]
        self._entries.append(HistoryEntry(description, before, after))
        self._index = len(self._entries)
        self.changed.emit()

    def undo(self) -> T:
        """Step back; return the value to restore (the undone entry's ``before``).

        Raises
        ------
        IndexError
            When there is nothing to undo.
        """
        if not self.can_undo:
            raise IndexError("nothing to undo")
        self._index -= 1
        value = self._entries[self._index].before
        self.changed.emit()
        return value

    def redo(self) -> T:
        """Step forward again; return the value to restore (the entry's ``after``).

        Raises
        ------
        IndexError
            When there is nothing to redo.
        """
        if not self.can_redo:
            raise IndexError("nothing to redo")
        value = self._entries[self._index].after
        self._index += 1
        self.changed.emit()
        return value

    def clear(self) -> None:
        """Forget every entry (after opening another document)."""
        self._entries.clear()
        self._index = 0
        self.changed.emit()

    def map_values(self, transform: Callable[[T], T]) -> None:
        """Replace every stored value ``v`` by ``transform(v)``.

        Used when something outside the history changes what all stored values
        must mean, e.g. a re-segmentation renumbers the regions: the history is
        rewritten so that undo keeps restoring values consistent with the new
        regions instead of being thrown away. ``transform`` is called once per
        distinct stored object (consecutive entries share their boundary value).
        """
        cache: dict[int, tuple[T, T]] = {}

        def mapped(value: T) -> T:
            # Keyed by id() with the original kept alive in the cache, so ids
            # cannot be reused by other objects during the loop.
            hit = cache.get(id(value))
            if hit is None:
                hit = (value, transform(value))
                cache[id(value)] = hit
            return hit[1]

        self._entries = [HistoryEntry(e.description, mapped(e.before), mapped(e.after)) for e in self._entries]
        self.changed.emit()

    @property
    def can_undo(self) -> bool:
        return self._index > 0

    @property
    def can_redo(self) -> bool:
        return self._index < len(self._entries)

    @property
    def undo_text(self) -> str:
        """Description of the step :meth:`undo` would revert, '' when none."""
        return self._entries[self._index - 1].description if self.can_undo else ""

    @property
    def redo_text(self) -> str:
        """Description of the step :meth:`redo` would re-apply, '' when none."""
        return self._entries[self._index].description if self.can_redo else ""

    @property
    def index(self) -> int:
        """Number of entries currently applied (0 = at the oldest state)."""
        return self._index

    def __len__(self) -> int:
        return len(self._entries)

    def entries(self) -> tuple[HistoryEntry[T], ...]:
        """All entries, oldest first (for tests and a history panel)."""
        return tuple(self._entries)
