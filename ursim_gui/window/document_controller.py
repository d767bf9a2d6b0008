"""File commands of the main window: open, save, import/export, reference, recovery, autosave.

Each command asks for a path (unless given one), calls the session, and turns a failure
into an error dialog plus a log entry. The session decides what is saved and whether the
document is dirty; a failed save leaves it dirty, so the title keeps its ``*``.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

from PySide6.QtCore import QObject, QTimer

from ursim_core.errors import UrsimError
from ursim_gui.model.autosave import Autosaver, find_recoverable, recover
from ursim_gui.views import file_dialogs
from ursim_gui.window import dialogs

__all__ = ["DocumentController", "MAP_FILTER", "JSON_FILTER", "DAT_FILTER"]

_log = logging.getLogger(__name__)
MAP_FILTER = "Maps (*.png *.jpg *.jpeg *.pgm *.tif *.tiff *.bmp *.yaml *.yml);;All files (*)"
JSON_FILTER = "Correspondences (*.json)"
DAT_FILTER = "Legacy correspondences (*.dat)"
REFERENCE_FILTER = "References (*.json *.dat)"
_FAILURES = (UrsimError, OSError, ValueError)


class DocumentController(QObject):
    """File commands over one session, with dialogs parented to ``window``."""

    def __init__(self, session, window, data_dir: Path):
        super().__init__(window)
        self.session = session
        self.window = window
        self.autosave_dir = Path(data_dir) / "autosave"
        self.autosave_dir.mkdir(parents=True, exist_ok=True)
        self.autosaver = Autosaver(session, self.autosave_dir)
        self.autosave_timer = QTimer(self)
        self.autosave_timer.setInterval(1000)
        self.autosave_timer.timeout.connect(self.flush_autosave)
        self.autosave_timer.start()
        self._autosave_failing = False
        session.dirty_changed.connect(lambda _dirty: self.update_title())
        session.path_changed.connect(lambda _path: self.update_title())
        session.error.connect(lambda message: dialogs.show_error(window, "Error", message))
        self.update_title()

    # ---- title and autosave --------------------------------------------------------------
    def update_title(self) -> None:
        """Window title from the session: file name, ``*`` while there are unsaved changes."""
        self.window.setWindowTitle(self.session.window_title())

    def flush_autosave(self) -> None:
        """The timer's call. Any failure is logged each time and shown once per failing streak."""
        try:
            written = self.autosaver.flush_if_due(time.monotonic())
        except Exception as error:
            # Whatever went wrong (disk, permissions, a value the codec refuses), the user
            # must know the work is not backed up, but one box, not one per tick.
            _log.warning("autosave failed: %s: %s", type(error).__name__, error)
            if not self._autosave_failing:
                self._autosave_failing = True
                dialogs.show_error(
                    self.window,
                    "Autosave failed",
                    f"The unsaved changes could not be backed up to {self.autosave_dir}:\n"
                    f"{type(error).__name__}: {error}\n\nSave the document to keep them; autosave keeps retrying.",
                )
            return
        if written:
            self._autosave_failing = False

    # ---- opening -------------------------------------------------------------------------
    def _ask_open(self, title: str, filters: str) -> Path | None:
        return file_dialogs.ask_open_path(self.window, title, filters)

    def open_map(self, side: str, path: Path | None = None) -> bool:
        """Open a map image or ROS YAML as ``side``'s map.

        A map that is not the one the document names starts a new, untitled document
        that keeps the other side's map (after asking about unsaved changes): the old
        cliques, reference and file belong to the old pair, and saving must never write
        them under the new map's name. The file is read first: one that cannot be read
        leaves the document as it was.
        """
        path = path or self._ask_open(f"Open {side} map", MAP_FILTER)
        if path is None:
            return False
        session = self.session
        try:
            map_ = session.read_map(path)
        except _FAILURES as error:
            dialogs.show_error(self.window, f"Cannot open the {side} map", str(error))
            return False
        return self.show_map(side, map_, f"opening another {side} map")

    def show_map(self, side: str, map_, what: str) -> bool:
        """Put a map already read (or drawn) on ``side``, by the rule of :meth:`open_map`: a map
        that is not the document's starts a new document, after asking about unsaved changes."""
        session = self.session
        # A drawing (no file) replaces only a drawing: a document naming a file is another pair.
        if map_.path is None:
            same = getattr(session.correspondences, side).path is None
        else:
            same = session.is_document_map(side, map_.path)
        if not same:
            if not self.confirm_discard(what):
                return False
            other = "metric" if side == "sketch" else "sketch"
            session.new_document(keep=[other])
        return self._try(f"Cannot open the {side} map", session.set_map, side, map_)

    def open_correspondences(self, path: Path | None = None) -> bool:
        """Open a correspondence JSON (and its maps), after offering to save changes."""
        if not self.confirm_discard("opening another file"):
            return False
        path = path or self._ask_open("Open correspondences", JSON_FILTER)
        if path is None or not self._try("Cannot open the correspondences", self.session.open, path):
            return False
        self._remember(path)
        self.segment_unsegmented()
        return True

    def segment_unsegmented(self) -> None:
        """Queue the segmentation of each map shown without one, with the segmentation panel's
        preset: a campaign's new pair, and a file that records no segmentation (ground truth
        clicked elsewhere, a generated example), whose points would otherwise show as nothing."""
        panel, jobs = self.window.segmentation_panel, self.window.jobs
        for side in ("sketch", "metric"):
            if self.session.map(side) is not None and self.session.segmentation(side) is None:
                box = panel.boxes[side]
                jobs.segment(side, box.preset.currentText(), box.overrides())

    def open_dropped(self, side: str, paths: list[Path]) -> None:
        """Files dropped on a view: a .json opens correspondences, anything else a map."""
        for path in paths:
            if path.suffix.lower() == ".json":
                self.open_correspondences(path)
            else:
                self.open_map(side, path)

    def load_reference(self, path: Path | None = None) -> bool:
        path = path or self._ask_open("Load reference", REFERENCE_FILTER)
        return path is not None and self._try("Cannot load the reference", self.session.load_reference, path)

    def import_dat(self, path: Path | None = None) -> bool:
        path = path or self._ask_open("Import .dat", DAT_FILTER)
        return path is not None and self._try("Cannot import the .dat file", self.session.import_dat, path)

    # ---- saving --------------------------------------------------------------------------
    def save(self) -> bool:
        """Save to the current file, or ask for one. True when the file was written."""
        if self.session.path is None:
            return self.save_as()
        if self.session.file_is_current():
            # Rewriting an unchanged file would only move its ``modified`` stamp (and its
            # modification time, which makes it look edited to others and to version control).
            self.window.statusBar().showMessage(f"No changes to save: {self.session.path} is up to date", 4000)
            return True
        return self._save_to(None)

    def save_as(self, path: Path | None = None) -> bool:
        if path is None:
            path = file_dialogs.ask_save_path(self.window, "Save correspondences", "correspondences.json", JSON_FILTER)
            if path is None:
                return False
        return self._save_to(path)

    def _save_to(self, path: Path | None) -> bool:
        from ursim_core.errors import FileChangedError

        try:
            self.session.save(path)
        except FileChangedError:
            # Someone else wrote the file since we read it: ask before overwriting their work.
            if not dialogs.ask_overwrite_changed(self.window, self.session.path):
                return False
            if not self._try("Save failed", lambda: self.session.save(path, overwrite_changed=True)):
                return False
        except _FAILURES as error:
            dialogs.show_error(self.window, "Save failed", str(error))
            return False
        self.autosaver.discard()
        self._remember(self.session.path)
        self.window.statusBar().showMessage(f"Saved {self.session.path}", 4000)
        return True

    def _remember(self, path: Path) -> None:
        preferences = getattr(self.window, "preferences", None)
        if preferences is not None:
            preferences.add_recent("documents", str(path))

    def export_dat(self, path: Path | None = None) -> bool:
        if path is None:
            path = file_dialogs.ask_save_path(self.window, "Export .dat", "correspondences.dat", DAT_FILTER)
            if path is None:
                return False
        return self._try("Export failed", self.session.export_dat, path)

    def confirm_discard(self, what: str) -> bool:
        """Before ``what`` replaces the document: True when it may go ahead."""
        if not self.session.dirty:
            return True
        answer = dialogs.ask_unsaved_changes(self.window, what)
        if answer == "save":
            return self.save()
        return answer == "discard"

    def discard_changes(self) -> None:
        """Forget the autosave without saving (scripted runs that must not prompt)."""
        self.autosaver.discard()

    def close_document(self) -> None:
        """The window closes normally: stop autosaving and remove the copy."""
        self.autosave_timer.stop()
        self.autosaver.close()

    # ---- recovery --------------------------------------------------------------------------
    def offer_recovery(self) -> bool:
        """If autosave files from an earlier run exist, offer them. True when one was restored."""
        paths = find_recoverable(self.autosave_dir)
        if not paths:
            return False
        chosen = dialogs.ask_recover(self.window, paths)
        if chosen is None:
            return False
        try:
            released = self.session.restore(recover(chosen), autosave=chosen)
        except _FAILURES as error:
            dialogs.show_error(self.window, "Recovery failed", str(error))
            return False
        # The drawings recovered are in memory again, and in this session's next autosave copy.
        for path in (chosen, *released):
            path.unlink(missing_ok=True)
        return True

    def _try(self, title: str, operation, *args) -> bool:
        try:
            operation(*args)
        except _FAILURES as error:
            dialogs.show_error(self.window, title, str(error))
            return False
        return True
