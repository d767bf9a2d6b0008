"""Qt-free model layer of URSIM Studio: all state and logic of the desktop app.

Nothing here imports PySide6 (an import-linter contract in pyproject.toml and a test
enforce it), so the model is tested without widgets and the Qt layers above it
(views, panels, tools, jobs, window) only render it and forward user input. It imports
only ``ursim_core``. See ``docs/gui_contract.md``.

- :mod:`~ursim_gui.model.signals`: :class:`Signal`, the change notification.
- :mod:`~ursim_gui.model.history`: :class:`History`, undo/redo of whole values.
- :mod:`~ursim_gui.model.session`: :class:`AnnotationSession`, the document being edited; its
  file, edit and evaluation operations are in ``session_documents``, ``session_edits`` and
  ``session_evaluation``, shared constants in ``session_values``.
- :mod:`~ursim_gui.model.autosave`: :class:`Autosaver` and crash recovery.
- :mod:`~ursim_gui.model.jobs`: :class:`SegmentJob`, :class:`MatchJob` for the worker process.
- :mod:`~ursim_gui.model.sketch_document`: the drawing of a new sketch (strokes, undo, save).
- :mod:`~ursim_gui.model.region_style`, :mod:`~ursim_gui.model.view_state`: colours, masks and
  badges the views draw, as arrays.
- :mod:`~ursim_gui.model.example`: the bundled example pair.
- :mod:`~ursim_gui.model.campaign`: a dataset's pairs, their files (naming rule) and statuses.
- :mod:`~ursim_gui.model.agreement`: annotator A vs B and the matcher vs each, CSV.
- :mod:`~ursim_gui.model.label_edits` (pure) and ``session_label_edits``: segmentation editing.
- :mod:`~ursim_gui.model.orientation`: the sketch's known turn and mirror.
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
