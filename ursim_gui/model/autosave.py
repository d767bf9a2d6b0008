"""Autosave and crash recovery of the correspondences being edited.

While a document has unsaved changes, :class:`Autosaver` keeps a copy in
``<folder>/<id>.autosave.json``: a normal correspondence file (atomic write) with one
extra top-level key, ``"autosave_of"``, the absolute path of the document it belongs to
(null for an untitled one), so that recovery can reopen the right maps and offer to save
to the right file. The copy disappears when the document becomes clean (saved, or
undone back to the saved state) and when the window closes normally; a copy found at
start-up therefore means the last run ended in a crash.

Writes are debounced: an edit marks the copy stale (:meth:`Autosaver.mark_dirty`), and
the view's timer calls :meth:`Autosaver.flush_if_due` with the current time. Time is
always passed in (``time.monotonic()`` in the app), so tests control it exactly.

Each autosaver holds a lock file ``<folder>/<id>.lock`` naming its process id while it
lives; :func:`find_recoverable` skips the copies of autosavers whose process still runs
(another window, or this one), so only a crashed run's copy is offered. A lock whose
process is gone is stale: its copy is recoverable.

The folder is, by priority: the constructor argument, ``$URSIM_AUTOSAVE_DIR``,
``$URSIM_GUI_DATA_DIR/autosave`` (the app's data folder), then the platform's user data
folder (``~/.local/share/ursim-studio/autosave`` on Linux).
"""

from __future__ import annotations

import dataclasses
import os
import sys
import time
import uuid
from collections.abc import Callable
from pathlib import Path

from ursim_core.correspondences import Correspondences, load_correspondences, save_correspondences
from ursim_core.io.atomic import atomic_write_bytes
from ursim_gui.model.session import AUTOSAVE_ORIGIN_KEY, SIDES, AnnotationSession

__all__ = [
    "AUTOSAVE_SUFFIX",
    "AUTOSAVE_DIR_ENV",
    "Autosaver",
    "default_autosave_folder",
    "find_recoverable",
    "recover",
    "recover_with_origin",
    "discard",
    "owner_running",
    "LOCK_SUFFIX",
]

AUTOSAVE_SUFFIX = ".autosave.json"
LOCK_SUFFIX = ".lock"
AUTOSAVE_DIR_ENV = "URSIM_AUTOSAVE_DIR"
_APP_DATA_ENV = "URSIM_GUI_DATA_DIR"
_APP_FOLDER = "ursim-studio"


def default_autosave_folder() -> Path:
    """Where autosave files go when no folder is given (see the module docstring).

    Examples
    --------
    >>> default_autosave_folder().name
    'autosave'
    """
    override = os.environ.get(AUTOSAVE_DIR_ENV)
    if override:
        return Path(override)
    app_data = os.environ.get(_APP_DATA_ENV)
    if app_data:
        return Path(app_data) / "autosave"
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = Path.home() / "Library" / "Application Support"
    else:
        base = Path(os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share")
    return base / _APP_FOLDER / "autosave"


def _instance_of(copy: Path) -> str:
    """The autosaver id in a copy's name ``<stem>-<id>.autosave.json``."""
    return copy.name[: -len(AUTOSAVE_SUFFIX)].rsplit("-", 1)[-1]


def _process_alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # it exists, owned by someone else
    except OSError:
        return False
    return True


def owner_running(folder: Path, instance_id: str) -> bool:
    """True when the lock of autosaver ``instance_id`` names a process that still runs."""
    try:
        text = (folder / f"{instance_id}{LOCK_SUFFIX}").read_text(encoding="ascii")
        pid = int(text.split()[0])
    except (OSError, ValueError, IndexError, UnicodeDecodeError):
        return False
    return _process_alive(pid)


def find_recoverable(folder: str | os.PathLike | None = None) -> list[Path]:
    """Autosave files of crashed runs in ``folder`` (default: :func:`default_autosave_folder`), newest first.

    A copy whose autosaver's process still runs (see the lock files in the module
    docstring) is not a crash copy and is left out. A missing folder simply has none.
    """
    folder = default_autosave_folder() if folder is None else Path(folder)
    if not folder.is_dir():
        return []
    found = [
        path
        for path in folder.glob(f"*{AUTOSAVE_SUFFIX}")
        if path.is_file() and not owner_running(folder, _instance_of(path))
    ]

    def modified(path: Path) -> float:
        try:
            return path.stat().st_mtime
        except OSError:
            return 0.0

    return sorted(found, key=lambda path: (-modified(path), path.name))


def recover(path: str | os.PathLike) -> Correspondences:
    """Read an autosave file.

    The value still carries ``extra["autosave_of"]`` (the document it belongs to);
    :meth:`AnnotationSession.restore` uses and removes it. Use
    :func:`recover_with_origin` to get the clean value and the path separately.

    Raises
    ------
    ursim_core.errors.FormatError
        The file is unreadable or not a correspondence file.
    """
    return load_correspondences(path)


def recover_with_origin(path: str | os.PathLike) -> tuple[Correspondences, Path | None]:
    """Read an autosave file: (correspondences without the autosave key, original document or None)."""
    corr = load_correspondences(path)
    extra = dict(corr.extra)
    origin = extra.pop(AUTOSAVE_ORIGIN_KEY, None)
    origin_path = Path(origin) if isinstance(origin, str) and origin else None
    return dataclasses.replace(corr, extra=extra), origin_path


def discard(path: str | os.PathLike) -> None:
    """Delete an autosave file, its edited label images and its drawn maps (no error when they are
    already gone)."""
    from ursim_gui.model.session_documents import drawn_map_path_for
    from ursim_gui.model.session_label_edits import labels_path_for

    path = Path(path)
    path.unlink(missing_ok=True)
    for side in SIDES:
        labels_path_for(path, side).unlink(missing_ok=True)
        drawn_map_path_for(path, side).unlink(missing_ok=True)


class Autosaver:
    """Keeps an autosave copy of a session's unsaved correspondences.

    Parameters
    ----------
    session : AnnotationSession
        Watched through its ``correspondences_changed``, ``dirty_changed`` and
        ``path_changed`` signals.
    folder : str or Path, optional
        Where the copy goes (created on first write); see :func:`default_autosave_folder`.
    delay_s : float, keyword-only
        Quiet time after the last edit before the copy is written.
    max_delay_s : float, keyword-only
        Longest time an edit may stay unsaved while edits keep coming (a continuous
        stream of edits must not postpone the copy forever).
    clock : callable, keyword-only
        ``() -> float`` seconds, the time base of edits marked through the signals; must
        be the one the caller passes to :meth:`flush_if_due` (``time.monotonic`` by
        default, as the app's timer).

    Notes
    -----
    The file name is the document's name plus an id unique to this autosaver, so a
    copy left by a crashed earlier run of the same document is never overwritten (the
    user may have postponed its recovery). The name follows a "save as".
    """

    def __init__(
        self,
        session: AnnotationSession,
        folder: str | os.PathLike | None = None,
        *,
        delay_s: float = 2.0,
        max_delay_s: float = 30.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.session = session
        self.folder = default_autosave_folder() if folder is None else Path(folder)
        self.delay_s = float(delay_s)
        self.max_delay_s = max(float(max_delay_s), self.delay_s)
        self._clock = clock
        self._instance_id = uuid.uuid4().hex[:12]
        self._first_pending: float | None = None
        self._last_pending: float | None = None
        self._written: Path | None = None
        self._closed = False
        self._lock: Path | None = None
        self._take_lock()
        session.correspondences_changed.connect(self._on_correspondences_changed)
        session.dirty_changed.connect(self._on_dirty_changed)
        session.path_changed.connect(self._on_path_changed)

    # ------------------------------------------------------------------ state
    @property
    def path(self) -> Path:
        """The file this session's copy is (or would be) written to."""
        document = self.session.path
        stem = "untitled" if document is None else document.stem
        return self.folder / f"{stem}-{self._instance_id}{AUTOSAVE_SUFFIX}"

    @property
    def pending(self) -> bool:
        """True when edits happened since the last write."""
        return self._last_pending is not None

    @property
    def written_path(self) -> Path | None:
        """The copy currently on disk, if any."""
        return self._written

    # ------------------------------------------------------------------ debouncing
    def mark_dirty(self, now: float) -> None:
        """Record an edit at time ``now`` (seconds); the copy is due ``delay_s`` later."""
        if self._first_pending is None:
            self._first_pending = now
        self._last_pending = now

    def due(self, now: float) -> bool:
        """True when a pending copy should be written at time ``now``."""
        if self._last_pending is None:
            return False
        return now - self._last_pending >= self.delay_s or now - self._first_pending >= self.max_delay_s

    def flush_if_due(self, now: float) -> bool:
        """Write the copy if it is due; True when a write (or a removal) happened.

        Raises
        ------
        Exception
            The write failed, for whatever reason (a full disk, a value the codec
            refuses...). The edit stays pending and is retried after another
            ``delay_s``; the caller reports the failure (autosave must not interrupt the user).
        """
        if self._closed or not self.due(now):
            return False
        try:
            self.flush()
        except Exception:
            # Back off instead of failing again on every timer tick.
            self._first_pending = self._last_pending = now
            raise
        return True

    def flush(self) -> None:
        """Write the copy now if the session is dirty, else remove any copy."""
        self._first_pending = self._last_pending = None
        if not self.session.dirty:
            self.discard()
            return
        corr = self.session.correspondences
        document = self.session.path
        extra = {**corr.extra, AUTOSAVE_ORIGIN_KEY: None if document is None else str(document)}
        target = self.path
        self.folder.mkdir(parents=True, exist_ok=True)
        if self._lock is None:
            self._take_lock()
        # ``now`` keeps the document's own timestamps: the copy must be the value in the
        # session, not a re-stamped one.
        # Edited segmentations go along as label images beside the copy, or a crash would lose them.
        copy, _drawn = self.session.drawn_maps_beside(dataclasses.replace(corr, extra=extra), target)
        copy = self.session.edited_labels_beside(copy, target)
        save_correspondences(copy, target, now=corr.modified)
        if self._written is not None and self._written != target:
            discard(self._written)
        self._written = target

    def discard(self) -> None:
        """Remove this session's copy (after a successful save or a deliberate discard).

        Only a file this autosaver wrote is removed: a copy left by a crashed earlier run
        of the same document stays until the user recovers or discards it.
        """
        if self._written is not None:
            discard(self._written)
        self._written = None
        self._first_pending = self._last_pending = None

    def close(self) -> None:
        """Clean shutdown: remove the copy and stop watching the session."""
        if self._closed:
            return
        self.discard()
        self._closed = True
        if self._lock is not None:
            self._lock.unlink(missing_ok=True)
            self._lock = None
        self.session.correspondences_changed.disconnect(self._on_correspondences_changed)
        self.session.dirty_changed.disconnect(self._on_dirty_changed)
        self.session.path_changed.disconnect(self._on_path_changed)

    def _take_lock(self) -> None:
        # Best effort: without a lock (read-only folder) a copy could only be offered
        # to another running window, never lost.
        lock = self.folder / f"{self._instance_id}{LOCK_SUFFIX}"
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(lock, f"{os.getpid()}\n".encode("ascii"))
        except OSError:
            return
        self._lock = lock

    # ------------------------------------------------------------------ session signals
    def _on_correspondences_changed(self) -> None:
        self.mark_dirty(self._clock())

    def _on_dirty_changed(self, dirty: bool) -> None:
        if not dirty:
            # Saved, or undone back to the saved state: nothing left to recover.
            self.discard()

    def _on_path_changed(self, _path) -> None:
        # The copy's name follows the document; a copy under the old name is obsolete.
        if self._written is not None and self._written != self.path:
            discard(self._written)
            self._written = None
            if self.session.dirty:
                self.mark_dirty(self._clock())
