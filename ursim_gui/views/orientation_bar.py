"""The turn and mirror buttons over the sketch view's top left corner.

They only ask: the holder of the sketch's orientation (the matching panel) answers, and the
view then shows the mirror button checked as the orientation says (:meth:`OrientationBar.show_mirrored`).
"""

from __future__ import annotations

from PySide6.QtCore import Qt, Signal
from PySide6.QtWidgets import QToolBar

__all__ = ["ORIENTATION_TIPS", "OrientationBar"]

#: Tooltips of the sketch's orientation buttons (the sketch view's and the matching panel's).
ORIENTATION_TIPS = {
    "left": "Turn the sketch 90° counter-clockwise and tell the matcher its orientation",
    "right": "Turn the sketch 90° clockwise and tell the matcher its orientation",
    "mirror": "Mirror the sketch left-right and tell the matcher (the mirror comes before the turn)",
}
#: Key of ORIENTATION_TIPS, text, degrees turned counter-clockwise (None: the mirror).
_BUTTONS = (("left", "⟲", 90.0), ("right", "⟳", -90.0), ("mirror", "⇆", None))


class OrientationBar(QToolBar):
    """Turn left, turn right and mirror buttons, hidden until there is a map to turn.

    Signals
    -------
    turn_requested(float) : degrees counter-clockwise
    mirror_requested(bool) : the mirror asked for
    """

    turn_requested = Signal(float)
    mirror_requested = Signal(bool)

    def __init__(self, parent, name: str):
        super().__init__(parent)
        self.setObjectName(name)
        self.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        self.setMovable(False)
        self.setAutoFillBackground(True)
        arrows = round(self.font().pointSizeF() * 1.5)  # the glyphs are small at the text's size
        self.setStyleSheet(f"QToolBar {{ border: 1px solid palette(mid); }} * {{ font-size: {arrows}pt; }}")
        #: The buttons by key of :data:`ORIENTATION_TIPS`.
        self.actions_by_key = {}
        self._mirrored = False
        for key, text, degrees in _BUTTONS:
            action = self.addAction(text)
            action.setObjectName(f"view_orient_{key}")
            action.setToolTip(ORIENTATION_TIPS[key])
            if degrees is None:
                action.setCheckable(True)
                action.triggered.connect(self._ask_mirror)
            else:
                action.triggered.connect(lambda _checked=False, degrees=degrees: self.turn_requested.emit(degrees))
            self.actions_by_key[key] = action
        self.adjustSize()
        self.hide()

    def show_mirrored(self, mirrored: bool) -> None:
        """Check the mirror button as the orientation set says."""
        self._mirrored = bool(mirrored)
        self.actions_by_key["mirror"].setChecked(self._mirrored)

    def _ask_mirror(self, mirrored: bool) -> None:
        # The button shows the orientation set, not its own click: show_mirrored checks it when
        # the holder of the orientation agrees.
        self.actions_by_key["mirror"].setChecked(self._mirrored)
        self.mirror_requested.emit(mirrored)
