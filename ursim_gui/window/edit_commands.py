"""Edit menu commands (link, unlink, delete, accept, reject, undo, redo, clear selection).

Each command reads the session's selection and calls one session method, so every key
press is exactly one undoable step; action enabled states follow the session.
"""

from __future__ import annotations

__all__ = ["EditCommands"]


class EditCommands:
    """Connects the edit actions to ``session`` and keeps their enabled state current."""

    def __init__(self, session, actions: dict):
        self.session = session
        self.actions = actions
        actions["link"].triggered.connect(self.link)
        actions["unlink"].triggered.connect(self.unlink)
        actions["delete_clique"].triggered.connect(self.delete_clique)
        actions["accept"].triggered.connect(lambda: self.set_status("accepted"))
        actions["reject"].triggered.connect(lambda: self.set_status("rejected"))
        actions["accept_all"].triggered.connect(self.accept_all)
        actions["relink"].triggered.connect(self.relink)
        actions["undo"].triggered.connect(self.undo)
        actions["redo"].triggered.connect(self.redo)
        actions["clear_selection"].triggered.connect(session.clear_selection)
        session.history_changed.connect(self.update_actions)
        session.selection_changed.connect(self.update_actions)
        session.correspondences_changed.connect(self.update_actions)
        self.update_actions()

    def _selected(self, side: str) -> list[int]:
        return sorted(self.session.selection.get(side, ()))

    def link(self) -> None:
        """New clique of the selected regions, or add them to the selected clique."""
        sketch, metric = self._selected("sketch"), self._selected("metric")
        if sketch or metric:
            self.session.link(sketch, metric, into=self.session.selected_clique)

    def unlink(self) -> None:
        """One undo step: the clicked region leaves the selected clique, or the selected regions all theirs.

        With a clique selected, only the region the user clicked (the session's focus)
        leaves it; the clique's other regions, and other cliques, are untouched. A clique
        picked from the table has no clicked region, so nothing is unlinked.
        """
        session = self.session
        if session.selected_clique is not None:
            if session.focus is not None:
                side, region = session.focus
                session.unlink(side, region, clique=session.selected_clique)
            return
        selected = {side: self._selected(side) for side in ("sketch", "metric")}
        if any(selected.values()):
            session.unlink_regions(selected)

    def delete_clique(self) -> None:
        if self.session.selected_clique is not None:
            self.session.delete_clique(self.session.selected_clique)

    def set_status(self, status: str) -> None:
        if self.session.selected_clique is not None:
            self.session.set_status(self.session.selected_clique, status)

    def accept_next(self) -> int | None:
        """Accept the selected clique and select the next one not yet reviewed; returns its id."""
        session = self.session
        current = session.selected_clique
        if current is not None:
            session.set_status(current, "accepted")
        cliques = session.correspondences.cliques
        ids = [clique.id for clique in cliques]
        start = ids.index(current) + 1 if current in ids else 0
        ordered = cliques[start:] + cliques[:start]
        following = next((clique.id for clique in ordered if clique.status is None), None)
        if following is not None:
            session.select_clique(following)
        return following

    def accept_all(self) -> None:
        """Accept every clique not yet reviewed (one undo step)."""
        pending = [clique.id for clique in self.session.correspondences.cliques if clique.status is None]
        if pending:
            self.session.set_statuses(pending, "accepted")

    def relink(self) -> None:
        """The selected clique's side of the last Ctrl+clicked region becomes that region (one step)."""
        session = self.session
        clique_id, focus = session.selected_clique, session.focus
        if clique_id is None or focus is None:
            return
        side, region = focus
        if region in getattr(session.clique(clique_id), f"{side}_regions"):
            return  # already its region: nothing to fix
        session.relink(clique_id, side, [region])

    def undo(self) -> None:
        if self.session.can_undo:
            self.session.undo()

    def redo(self) -> None:
        if self.session.can_redo:
            self.session.redo()

    def update_actions(self, *_args) -> None:
        session, actions = self.session, self.actions
        has_clique = session.selected_clique is not None
        has_regions = any(session.selection.get(side) for side in ("sketch", "metric"))
        actions["undo"].setEnabled(session.can_undo)
        actions["redo"].setEnabled(session.can_redo)
        actions["undo"].setText(f"&Undo {session.undo_text}" if session.can_undo else "&Undo")
        actions["redo"].setText(f"&Redo {session.redo_text}" if session.can_redo else "&Redo")
        actions["link"].setEnabled(has_regions)
        actions["unlink"].setEnabled(has_regions)
        for key in ("delete_clique", "accept", "reject", "relink"):
            actions[key].setEnabled(has_clique)
        actions["accept_all"].setEnabled(any(clique.status is None for clique in session.correspondences.cliques))
