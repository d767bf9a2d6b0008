"""Qt-free model layer of URSIM Studio: all state and logic of the desktop app.

Nothing here imports PySide6 (a test enforces it), so the model is tested without
widgets and the views in ``ursim_gui`` only render it and forward user input.
See ``docs/gui_contract.md``.

- :mod:`~ursim_gui.model.signals`: :class:`Signal`, the change notification.
- :mod:`~ursim_gui.model.history`: :class:`History`, undo/redo of whole values.
- :mod:`~ursim_gui.model.session`: :class:`AnnotationSession`, the document being edited.
- :mod:`~ursim_gui.model.autosave`: :class:`Autosaver` and crash recovery.
- :mod:`~ursim_gui.model.jobs`: :class:`SegmentJob`, :class:`MatchJob` for worker threads.
"""

from ursim_gui.model.autosave import Autosaver, discard, find_recoverable, recover, recover_with_origin
from ursim_gui.model.history import History, HistoryEntry
from ursim_gui.model.jobs import JobCancelled, MatchJob, SegmentJob
from ursim_gui.model.session import SIDES, AnnotationSession, color_of_clique
from ursim_gui.model.signals import Signal

__all__ = [
    "SIDES",
    "AnnotationSession",
    "Autosaver",
    "History",
    "HistoryEntry",
    "JobCancelled",
    "MatchJob",
    "SegmentJob",
    "Signal",
    "color_of_clique",
    "discard",
    "find_recoverable",
    "recover",
    "recover_with_origin",
]
