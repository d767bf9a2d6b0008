"""The selection of :class:`~ursim_gui.model.session.AnnotationSession`: regions on each side, a
clique, and the region the user last picked by itself.

A mixin over the session's ``_selection``, ``_selected_clique``, ``_focus`` and ``_corr``;
every change emits ``selection_changed`` once, and a call that would change nothing emits
nothing. Selecting is not an edit: it records no history.
"""

from __future__ import annotations

from collections.abc import Iterable

from ursim_gui.model.session_values import SIDES, _check_side

__all__ = ["SelectionOperations"]


class SelectionOperations:
    """What is selected in a session, and the operations that change it."""

    @property
    def selection(self) -> dict[str, frozenset[int]]:
        return dict(self._selection)

    @property
    def selected_clique(self) -> int | None:
        return self._selected_clique

    @property
    def focus(self) -> tuple[str, int] | None:
        """``(side, region)`` the user last picked by itself (what U unlinks), or None."""
        return self._focus

    def select(self, side: str, regions: Iterable[int], *, add: bool = False) -> None:
        """Select regions of ``side``.

        With ``add`` the regions join the current selection and the selected clique
        stays (so a region can be added to it); without, they replace the side's
        selection and the selected clique is cleared.

        A plain selection after a selected clique also clears the other side: those
        regions were the clique's, not picked by the user, and linking must not pull them in.
        """
        _check_side(side)
        chosen = frozenset(int(region) for region in regions)
        new_selection = dict(self._selection)
        new_selection[side] = new_selection[side] | chosen if add else chosen
        if not add and self._selected_clique is not None:
            new_selection[SIDES[1 - SIDES.index(side)]] = frozenset()
        new_clique = self._selected_clique if add else None
        new_focus = (side, next(iter(chosen))) if len(chosen) == 1 else (self._focus if add else None)
        if new_selection == self._selection and new_clique == self._selected_clique and new_focus == self._focus:
            return
        self._selection = new_selection
        self._selected_clique = new_clique
        self._focus = new_focus
        self.selection_changed.emit()

    def select_clique(self, clique_id: int | None, *, focus: tuple[str, int] | None = None) -> None:
        """Select a clique (its regions become the selection on both sides), or none.

        ``focus`` is the ``(side, region)`` the user clicked to select it (what U then
        unlinks from this clique); None when it was picked from a list.
        """
        if clique_id is None:
            if self._selected_clique is None:
                return
            self._selected_clique = None
            self._focus = None
            self.selection_changed.emit()
            return
        clique = self._corr.clique(clique_id)
        self._selected_clique = clique.id
        self._focus = None if focus is None else (_check_side(focus[0]), int(focus[1]))
        self._selection = {
            "sketch": frozenset(clique.sketch_regions),
            "metric": frozenset(clique.metric_regions),
        }
        self.selection_changed.emit()

    def clear_selection(self) -> None:
        """Select nothing."""
        if self._selected_clique is None and not any(self._selection.values()):
            return
        self._selection = {side: frozenset() for side in SIDES}
        self._selected_clique = None
        self._focus = None
        self.selection_changed.emit()

    def _clear_side_selection(self, side: str) -> bool:
        changed = bool(self._selection[side]) or self._selected_clique is not None
        self._selection = {**self._selection, side: frozenset()}
        self._selected_clique = None
        self._focus = None
        return changed
