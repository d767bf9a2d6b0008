"""Every keyboard shortcut and mouse gesture of the app, and the F1 sheet that lists them.

:data:`SHORTCUTS` is the single source of truth: the main window creates its actions
from it and the sheet displays it, so the sheet cannot drift from the real bindings.
"""

from __future__ import annotations

from dataclasses import dataclass

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QGuiApplication, QKeySequence
from PySide6.QtWidgets import QDialog, QDialogButtonBox, QHeaderView, QTableWidget, QTableWidgetItem, QVBoxLayout

__all__ = ["ActionSpec", "SHORTCUTS", "MOUSE_GESTURES", "make_action", "ShortcutSheet"]


@dataclass(frozen=True)
class ActionSpec:
    """One user command: id, menu text, key sequences (first is shown) and what it does.

    ``toolbar`` is its label on the toolbar when the menu text is too long for it (the toolbar must
    fit a 1280-pixel window; the tooltip says the rest).
    """

    id: str
    text: str
    keys: tuple[str, ...]
    description: str
    group: str
    checkable: bool = False
    toolbar: str = ""


SHORTCUTS: tuple[ActionSpec, ...] = (
    ActionSpec("new_sketch", "&New sketch…", ("Ctrl+N",), "Draw a sketch on a blank canvas", "File"),
    ActionSpec(
        "open_campaign",
        "Open &campaign…",
        ("Ctrl+Shift+O",),
        "Open a dataset folder, a folder of sketches with one metric map, or a campaign manifest",
        "File",
    ),
    ActionSpec(
        "open_sketch", "Open &sketch…", ("Ctrl+1",), "Open the sketch map, the left view (image or ROS YAML)", "File"
    ),
    ActionSpec(
        "open_metric",
        "Open &metric map…",
        ("Ctrl+2",),
        "Open the metric map, the right view (image or ROS YAML)",
        "File",
        toolbar="Open metric",
    ),
    ActionSpec(
        "open_correspondences", "&Open correspondences…", ("Ctrl+O",), "Open a correspondence JSON and its maps", "File"
    ),
    ActionSpec("save", "&Save", ("Ctrl+S",), "Save the correspondences", "File"),
    ActionSpec("save_as", "Save &as…", ("Ctrl+Shift+S",), "Save the correspondences to a new file", "File"),
    ActionSpec("import_dat", "&Import .dat…", (), "Replace the correspondences by a legacy .dat file", "File"),
    ActionSpec("export_dat", "&Export .dat…", (), "Write the correspondences as a legacy .dat file", "File"),
    ActionSpec(
        "export_figure", "Export &figure…", ("Ctrl+E",), "PNG of both maps with the matches and a legend", "File"
    ),
    ActionSpec("quit", "&Quit", ("Ctrl+Q",), "Close the window (asks to save changes)", "File"),
    ActionSpec("undo", "&Undo", ("Ctrl+Z",), "Undo the last edit", "Edit"),
    ActionSpec("redo", "&Redo", ("Ctrl+Shift+Z", "Ctrl+Y"), "Redo the last undone edit", "Edit"),
    ActionSpec(
        "link",
        "&Link selected regions",
        ("L",),
        "New clique of the selected regions (or add them to the selected clique)",
        "Edit",
        toolbar="Link",
    ),
    ActionSpec(
        "unlink", "U&nlink region", ("U",), "Remove the selected region(s) from their cliques", "Edit", toolbar="Unlink"
    ),
    ActionSpec("delete_clique", "&Delete clique", ("Delete",), "Delete the selected clique", "Edit"),
    ActionSpec("accept", "&Accept clique", ("Y",), "Mark the selected clique accepted", "Edit", toolbar="Accept"),
    ActionSpec(
        "accept_next",
        "Accept and &next clique",
        ("Space",),
        "Accept the selected clique, then select and zoom to the next one to review",
        "Edit",
    ),
    ActionSpec("reject", "Re&ject clique", ("R",), "Mark the selected clique rejected", "Edit", toolbar="Reject"),
    ActionSpec(
        "relink",
        "Re&link clique",
        ("E",),
        "Replace the selected clique's side by the region Ctrl+clicked last (fixes a wrong match)",
        "Edit",
    ),
    ActionSpec("accept_all", "Accept a&ll", ("Ctrl+Shift+Y",), "Accept every clique not yet reviewed", "Edit"),
    ActionSpec(
        "match",
        "&Match again",
        ("Ctrl+M",),
        "Run the matcher with the panel's settings; the cliques you linked, accepted or rejected are kept "
        "and steer the answer (best after linking what it missed)",
        "Edit",
    ),
    ActionSpec(
        "match_runner_up",
        "Match as read &next best",
        ("Ctrl+Shift+M",),
        "Tell the matcher the reading it ranked next after the last match and match again (Undo gives the answer back)",
        "Edit",
    ),
    ActionSpec(
        "compare_readings",
        "&Compare the readings…",
        ("Ctrl+Shift+R",),
        "See the sketch turned as each reading the last match ranked, beside the metric map, and match in one",
        "Edit",
    ),
    ActionSpec("clear_selection", "Clear selection", ("Esc",), "Deselect all regions", "Edit"),
    ActionSpec(
        "fit", "&Fit to window", ("F",), "Fit each map's drawn part (its free space and a margin) to its view", "View"
    ),
    ActionSpec("zoom_clique", "&Zoom to clique", ("Z",), "Zoom both views to the selected clique", "View"),
    ActionSpec("zoom_in", "Zoom &in", ("Ctrl++", "Ctrl+="), "Zoom both views in", "View"),
    ActionSpec("zoom_out", "Zoom &out", ("Ctrl+-",), "Zoom both views out", "View"),
    ActionSpec("link_zoom", "&Linked zoom", ("Ctrl+K",), "Zoom both views together", "View", checkable=True),
    ActionSpec(
        "connectors",
        "&Connector lines",
        ("C",),
        "Draw lines between matched regions",
        "View",
        checkable=True,
        toolbar="Connectors",
    ),
    ActionSpec("outlines", "Region &outlines", ("O",), "Show region outlines", "View", checkable=True),
    ActionSpec("region_ids", "Region &ids", ("I",), "Show region ids", "View", checkable=True),
    ActionSpec("dark_theme", "&Dark theme", (), "Dark window and map backgrounds (remembered)", "View", checkable=True),
    ActionSpec("graph", "Adjacency &graph", ("G",), "Show the region adjacency graph", "View", checkable=True),
    ActionSpec(
        "laid_sketch",
        "&Laid sketch",
        ("Shift+L",),
        "Outline the sketch's regions on the metric map where the matcher laid and bent them",
        "View",
        checkable=True,
    ),
    ActionSpec(
        "merge_regions", "&Merge regions", ("M",), "Merge the regions selected on one map (Ctrl+click them)", "Segment"
    ),
    ActionSpec(
        "split_mode", "&Split region", ("K",), "Draw a line across a region to cut it in two", "Segment", checkable=True
    ),
    ActionSpec("paint_wall_mode", "&Paint wall", ("W",), "Draw a wall stroke on a map", "Segment", checkable=True),
    ActionSpec(
        "erase_wall_mode",
        "&Erase wall",
        ("Shift+W",),
        "Erase a wall stroke (joins it to the region around)",
        "Segment",
        checkable=True,
    ),
    ActionSpec(
        "goal_tool",
        "&Goal tool",
        ("T",),
        "Click the sketch: the goal it gives in the metric map",
        "Navigate",
        checkable=True,
    ),
    ActionSpec(
        "route_tool",
        "&Route tool",
        ("P",),
        "Drag a route on the sketch: waypoints in the metric map",
        "Navigate",
        checkable=True,
    ),
    ActionSpec(
        "goal_nearest",
        "Goal at the &nearest matched region",
        ("Shift+T",),
        "After a tap on an unmatched region: place the goal in the nearest matched one",
        "Navigate",
    ),
    ActionSpec("clear_navigation", "&Clear goals and route", (), "Remove the goals and the route", "Navigate"),
    ActionSpec(
        "export_navigation", "Export goals as &JSON…", (), "Goals and route as PoseStamped-like JSON", "Navigate"
    ),
    ActionSpec(
        "export_nav2",
        "Export nav2 &waypoints…",
        (),
        "The route (or goals) as nav2's RViz-panel waypoint file",
        "Navigate",
    ),
    ActionSpec("next_pair", "&Next pair", ("D",), "Save this pair and open the next one of the campaign", "Campaign"),
    ActionSpec("prev_pair", "&Previous pair", ("A",), "Save this pair and open the previous one", "Campaign"),
    ActionSpec("shortcuts", "&Keyboard shortcuts", ("F1",), "This sheet", "Help"),
)

#: The sheet's column of what each key does (the one that stretches).
ACTION_COLUMN = 2
#: The sheet's size where the screen has room for it.
_SHEET_SIZE = (860, 680)

MOUSE_GESTURES: tuple[tuple[str, str], ...] = (
    ("Click", "Select a region (and its clique)"),
    ("Ctrl+Click", "Add a region to the selection"),
    ("Wheel", "Zoom around the cursor"),
    ("Drag / middle drag", "Pan"),
    ("Hover", "Highlight the partner regions in the other view"),
    ("Drop a file", "Open it as this view's map"),
    ("Click / drag (goal / route tool)", "Place a goal / draw a route on the sketch"),
)


def make_action(spec: ActionSpec, parent) -> QAction:
    """A QAction for ``spec`` with its shortcuts, tooltip and object name (``action_<id>``)."""
    action = QAction(spec.text, parent)
    action.setObjectName(f"action_{spec.id}")
    # Toolbar label fixed once: menu texts such as "Undo Link sketch 3 to metric 5"
    # change with the history and would make the toolbar jump.
    action.setIconText(spec.toolbar or spec.text.replace("&", "").replace("…", ""))
    action.setShortcuts([QKeySequence(key) for key in spec.keys])
    action.setShortcutContext(Qt.ShortcutContext.WindowShortcut)
    action.setCheckable(spec.checkable)
    keys = f" ({spec.keys[0]})" if spec.keys else ""
    action.setToolTip(f"{spec.description}{keys}")
    action.setStatusTip(spec.description)
    return action


class ShortcutSheet(QDialog):
    """The F1 dialog: one row per shortcut and mouse gesture, grouped by menu."""

    def __init__(self, parent=None):
        super().__init__(parent)
        self.setWindowTitle("Keyboard shortcuts")
        self.setObjectName("shortcut_sheet")
        rows = [
            (
                s.group,
                " or ".join(QKeySequence(k).toString(QKeySequence.SequenceFormat.NativeText) for k in s.keys),
                s.description,
            )
            for s in SHORTCUTS
            if s.keys
        ]
        rows += [("Mouse", gesture, what) for gesture, what in MOUSE_GESTURES]
        self.table = QTableWidget(len(rows), 3, self)
        self.table.setHorizontalHeaderLabels(["Group", "Keys", "Action"])
        for row, values in enumerate(rows):
            for column, value in enumerate(values):
                self.table.setItem(row, column, QTableWidgetItem(value))
        self.table.setEditTriggers(QTableWidget.EditTrigger.NoEditTriggers)
        # Group and keys as wide as their longest entry, the action takes the rest and wraps onto
        # as many lines as it needs: never elided ("…").
        header = self.table.horizontalHeader()
        header.setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(ACTION_COLUMN, QHeaderView.ResizeMode.Stretch)
        self.table.setWordWrap(True)
        self.table.setTextElideMode(Qt.TextElideMode.ElideNone)
        self.table.verticalHeader().setVisible(False)
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.ResizeToContents)
        buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Close, self)
        buttons.rejected.connect(self.reject)
        layout = QVBoxLayout(self)
        layout.addWidget(self.table)
        layout.addWidget(buttons)
        self.resize(*self._fitting_size(parent))

    @staticmethod
    def _fitting_size(parent) -> tuple[int, int]:
        """Wide enough for most actions on one line, never wider or taller than the screen allows."""
        screen = (parent.screen() if parent is not None else None) or QGuiApplication.primaryScreen()
        if screen is None:
            return _SHEET_SIZE
        available = screen.availableGeometry()
        return min(_SHEET_SIZE[0], int(available.width() * 0.9)), min(_SHEET_SIZE[1], int(available.height() * 0.9))

    def key_texts(self) -> list[str]:
        """The Keys column (for tests and accessibility checks)."""
        return [self.table.item(row, 1).text() for row in range(self.table.rowCount())]
