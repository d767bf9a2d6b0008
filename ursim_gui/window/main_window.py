"""Main window: composition of the views, panels, menus and controllers. No annotation logic.

Layout: the sketch and metric views side by side in a splitter (with the connector
overlay over both), the segmentation and matching panels docked on the right, the
correspondence table, anchors and evaluation docked below.
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QApplication,
    QDockWidget,
    QLabel,
    QMainWindow,
    QScrollArea,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from ursim_gui.jobs.controller import JobController
from ursim_gui.model.orientation import SketchOrientation
from ursim_gui.model.pair_settings import MapIdentities, recorded_settings
from ursim_gui.model.session import AnnotationSession
from ursim_gui.model.wording import counted
from ursim_gui.panels.agreement_panel import AgreementPanel
from ursim_gui.panels.anchors_list import AnchorsList
from ursim_gui.panels.campaign_panel import CampaignPanel
from ursim_gui.panels.correspondence_table import CorrespondenceTable
from ursim_gui.panels.evaluation_panel import EvaluationPanel
from ursim_gui.panels.matching_panel import MatchingPanel
from ursim_gui.panels.segmentation_panel import SegmentationPanel
from ursim_gui.tools.segmentation_editor import SegmentationEditor
from ursim_gui.views.connectors import ConnectorOverlay
from ursim_gui.views.map_view import MapView
from ursim_gui.views.session_binding import SIDES, ViewBinding
from ursim_gui.views.status_bar import CursorStatusBar
from ursim_gui.views.theme import apply_theme
from ursim_gui.window.agreement_controller import AgreementController
from ursim_gui.window.campaign_controller import CampaignController
from ursim_gui.window.dock_tabs import hide_stray_tab_bars
from ursim_gui.window.document_controller import DocumentController
from ursim_gui.window.edit_commands import EditCommands
from ursim_gui.window.navigation_controller import NavigationController
from ursim_gui.window.preferences import Preferences
from ursim_gui.window.shortcuts import SHORTCUTS, ShortcutSheet, make_action
from ursim_gui.window.window_commands import WindowTools

__all__ = ["MainWindow"]

_log = logging.getLogger(__name__)
_TOOLBAR = (
    "open_sketch",
    "open_metric",
    "open_correspondences",
    "save",
    None,
    "undo",
    "redo",
    None,
    "link",
    "unlink",
    "accept",
    "reject",
    None,
    "fit",
    "link_zoom",
    "connectors",
    None,
    "goal_tool",
    "route_tool",
)
_DISPLAY = ("outlines", "region_ids", "graph", "laid_sketch")
#: The right column's share of the window's width on a first start, and its widest (pixels).
_PANEL_COLUMN_SHARE, _PANEL_COLUMN_MAX = 0.3, 560
#: Display toggles remembered between runs, with their first-run state.
_TOGGLE_DEFAULTS = {
    "dark_theme": False,
    "outlines": True,
    "region_ids": False,
    "graph": False,
    "laid_sketch": True,
    "connectors": False,
    "link_zoom": False,
}


class MainWindow(QMainWindow):
    """The app window over one :class:`AnnotationSession`.

    Parameters
    ----------
    data_dir : Path
        User data folder (autosave files live in ``data_dir / 'autosave'``).
    session : AnnotationSession, optional
        The session to show (a new one by default).
    """

    def __init__(self, data_dir: Path, session: AnnotationSession | None = None):
        super().__init__()
        self.setObjectName("main_window")
        self._shown = False
        self.preferences = Preferences(data_dir, self)
        self.session = session if session is not None else AnnotationSession(annotator=self.preferences.annotator())
        self.actions = {spec.id: make_action(spec, self) for spec in SHORTCUTS}
        for action in self.actions.values():
            self.addAction(action)  # shortcuts work wherever the focus is in the window
        self.views = {side: MapView(side) for side in SIDES}
        self._build_centre()
        self.status = CursorStatusBar(self)
        self.setStatusBar(self.status)
        self.documents = DocumentController(self.session, self, data_dir)
        self.jobs = JobController(self.session, self.status, self)
        self.binding = ViewBinding(self.session, self.views, self.connectors)
        self.edits = EditCommands(self.session, self.actions)
        self.segmentation_panel = SegmentationPanel({key: self.actions[key] for key in _DISPLAY})
        self.matching_panel = MatchingPanel()
        self.table = CorrespondenceTable(self.session)
        self.anchors = AnchorsList(self.session)
        self.evaluation = EvaluationPanel(self.session)
        self.campaign_panel = CampaignPanel()
        self.agreement_panel = AgreementPanel()
        self._build_docks()
        self._build_menus()
        self._connect()
        self.campaigns = CampaignController(self, self.campaign_panel, data_dir)
        self.agreement = AgreementController(self, self.agreement_panel)
        self._connect_review()
        for name, default in _TOGGLE_DEFAULTS.items():
            self.actions[name].setChecked(self.preferences.toggle(name, default))
        self._layout_restored = self.preferences.restore_window(self)
        if not self._layout_restored:
            self._fit_to_screen()

    # ---- layout ------------------------------------------------------------------------------
    def _build_centre(self) -> None:
        host = QWidget()
        self.splitter = QSplitter(Qt.Orientation.Horizontal)
        self.splitter.setChildrenCollapsible(False)
        self.view_titles = {}
        for side, view in self.views.items():
            pane = QWidget()
            layout = QVBoxLayout(pane)
            layout.setContentsMargins(2, 2, 2, 2)
            title = QLabel(side.capitalize())
            title.setObjectName(f"{side}_title")
            title.setStyleSheet("font-weight: 600; padding: 2px 4px;")
            layout.addWidget(title)
            layout.addWidget(view, 1)
            self.view_titles[side] = title
            self.splitter.addWidget(pane)
        layout = QVBoxLayout(host)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.addWidget(self.splitter)
        self.connectors = ConnectorOverlay(host, self.views["sketch"], self.views["metric"])
        self.setCentralWidget(host)

    def _dock(self, title: str, widget: QWidget, area, name: str, scroll: bool = False) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(name)
        if scroll:
            holder = QScrollArea()
            holder.setWidgetResizable(True)
            holder.setWidget(widget)
            # Scrolled up and down only: the dock is kept as wide as the panel needs.
            holder.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
            holder.setMinimumWidth(widget.minimumSizeHint().width() + holder.verticalScrollBar().sizeHint().width())
            widget = holder
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        return dock

    def _build_docks(self) -> None:
        right, bottom = Qt.DockWidgetArea.RightDockWidgetArea, Qt.DockWidgetArea.BottomDockWidgetArea
        # The right column runs to the bottom: the panels get the full height.
        self.setCorner(Qt.Corner.BottomRightCorner, right)
        self.docks = {
            "segmentation": self._dock(
                "Segmentation", self.segmentation_panel, right, "dock_segmentation", scroll=True
            ),
            "matching": self._dock("Matching", self.matching_panel, right, "dock_matching", scroll=True),
            "table": self._dock("Correspondences", self.table, bottom, "dock_table"),
            "evaluation": self._dock("Evaluation", self.evaluation, bottom, "dock_evaluation"),
            "anchors": self._dock("Anchors", self.anchors, bottom, "dock_anchors"),
            "campaign": self._dock("Campaign", self.campaign_panel, right, "dock_campaign"),
            "agreement": self._dock("Agreement", self.agreement_panel, bottom, "dock_agreement"),
        }
        self.tabifyDockWidget(self.docks["evaluation"], self.docks["agreement"])
        self.tabifyDockWidget(self.docks["segmentation"], self.docks["campaign"])
        self.docks["segmentation"].raise_()
        self.tabifyDockWidget(self.docks["evaluation"], self.docks["anchors"])
        self.docks["evaluation"].raise_()
        self.docks["segmentation"].setMinimumWidth(300)
        self.resizeDocks([self.docks["table"]], [240], Qt.Orientation.Vertical)
        # Half the right column each: the matching dock shows Match, the orientation and the
        # answer without scrolling (a quarter showed none of them); both scroll on a laptop screen.
        self.resizeDocks([self.docks["segmentation"], self.docks["matching"]], [1, 1], Qt.Orientation.Vertical)
        self.resizeDocks([self.docks["table"], self.docks["evaluation"]], [800, 380], Qt.Orientation.Horizontal)

    def _build_menus(self) -> None:
        groups: dict[str, list[str]] = {}
        for spec in SHORTCUTS:
            groups.setdefault(spec.group, []).append(spec.id)
        for group, ids in groups.items():
            menu = self.menuBar().addMenu(f"&{group}")
            for action_id in ids:
                if action_id in ("quit", "link", "fit", "link_zoom", "shortcuts"):
                    menu.addSeparator()
                menu.addAction(self.actions[action_id])
            if group == "View":
                menu.addSeparator()
                for dock in self.docks.values():
                    menu.addAction(dock.toggleViewAction())
            if group == "File":
                self.recent_menu = menu.addMenu("Open &recent")
                self.recent_menu.setObjectName("recent_menu")
                self.recent_menu.aboutToShow.connect(self._fill_recent_menu)
        toolbar = self.addToolBar("Main")
        toolbar.setObjectName("main_toolbar")
        toolbar.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        for action_id in _TOOLBAR:
            toolbar.addSeparator() if action_id is None else toolbar.addAction(self.actions[action_id])

    # ---- wiring --------------------------------------------------------------------------------
    def _connect(self) -> None:
        a, docs = self.actions, self.documents
        a["open_sketch"].triggered.connect(lambda: docs.open_map("sketch"))
        a["open_metric"].triggered.connect(lambda: docs.open_map("metric"))
        a["open_correspondences"].triggered.connect(lambda: docs.open_correspondences())
        a["save"].triggered.connect(docs.save)
        a["save_as"].triggered.connect(lambda: docs.save_as())
        a["import_dat"].triggered.connect(lambda: docs.import_dat())
        a["export_dat"].triggered.connect(lambda: docs.export_dat())
        a["export_figure"].triggered.connect(lambda: self.tools.export_figure())
        a["new_sketch"].triggered.connect(lambda: self.tools.new_sketch())
        a["quit"].triggered.connect(self.close)
        a["shortcuts"].triggered.connect(self.show_shortcuts)
        a["fit"].triggered.connect(self.fit_views)
        a["zoom_in"].triggered.connect(lambda: self._zoom_all(1.25))
        a["zoom_out"].triggered.connect(lambda: self._zoom_all(0.8))
        a["connectors"].toggled.connect(self.connectors.setVisible)
        a["dark_theme"].toggled.connect(lambda on: apply_theme("dark" if on else "system"))
        a["outlines"].toggled.connect(lambda on: [v.set_outlines_visible(on) for v in self.views.values()])
        a["region_ids"].toggled.connect(lambda on: [v.set_ids_visible(on) for v in self.views.values()])
        a["graph"].toggled.connect(lambda on: [v.set_graph_visible(on) for v in self.views.values()])
        a["laid_sketch"].toggled.connect(self.binding.set_laid_visible)
        self.segmentation_panel.opacity_changed.connect(
            lambda value: [v.set_overlay_opacity(value) for v in self.views.values()]
        )
        for side, view in self.views.items():
            view.files_dropped.connect(lambda paths, side=side: docs.open_dropped(side, paths))
            view.cursor_moved.connect(lambda row, col, side=side: self.tools.show_cursor(side, row, col))
            view.zoom_changed.connect(lambda factor, side=side: self._zoom_changed(side, factor))
            box = self.segmentation_panel.boxes[side]
            box.preset.setCurrentText(self.session.segmentation_preset(side))
            box.preset.currentTextChanged.connect(
                lambda preset, side=side: self.session.set_segmentation_preset(side, preset)
            )
            box.segment_requested.connect(
                lambda s, method, preset, params: self.jobs.segment(s, preset, params, method=method)
            )
            box.load_labels_requested.connect(lambda s: self.tools.load_label_image(s))
        self.matching_panel.match_requested.connect(self.jobs.match)
        self.actions["match"].triggered.connect(lambda: self.jobs.match(self.matching_panel.config()))
        self.actions["match_runner_up"].triggered.connect(self.matching_panel.match_runner_up)
        self.actions["compare_readings"].triggered.connect(lambda: self.tools.compare_readings())
        self.matching_panel.readings_requested.connect(lambda: self.tools.compare_readings())
        self.matching_panel.runner_up_changed.connect(self._update_ready)
        self.matching_panel.orientation_changed.connect(
            lambda o: self.views["sketch"].set_orientation(o.angle or 0.0, o.mirrored)
        )
        # The sketch view's own turn and mirror buttons ask the panel, which holds the orientation.
        self.views["sketch"].turn_requested.connect(self.matching_panel.turn)
        self.views["sketch"].mirror_requested.connect(self.matching_panel.set_mirrored)
        self.evaluation.load_requested.connect(lambda: docs.load_reference())
        self.jobs.busy_changed.connect(lambda _busy: self._update_ready())
        self.session.segmentation_changed.connect(lambda _side: self._update_ready())
        self.session.segmentation_changed.connect(self._show_summary)
        self.session.map_changed.connect(self._show_map_title)
        # A drawn map gets its file when the document is first saved (and named).
        self.session.path_changed.connect(lambda _path: [self._show_map_title(side) for side in SIDES])
        self._identities = MapIdentities({side: self._digest_of(side) for side in SIDES})
        self._record_reads_this_sketch = True
        self.session.map_changed.connect(self._forget_settings_of_another_map)
        self.session.document_opened.connect(self._use_recorded_settings)
        self.session.correspondences_changed.connect(lambda *_: self._show_match_summary())
        self.tools = WindowTools(self)
        self._update_ready()
        self._show_match_summary()

    def _fill_recent_menu(self) -> None:
        """Recent campaigns and correspondence files (from the preferences), newest first."""
        menu = self.recent_menu
        menu.clear()
        for kind, opener in (("campaigns", self.campaigns.open), ("documents", self.documents.open_correspondences)):
            for path in self.preferences.recent(kind):
                menu.addAction(path, lambda path=path, opener=opener: opener(Path(path)))
            menu.addSeparator()
        if not menu.actions() or all(action.isSeparator() for action in menu.actions()):
            menu.addAction("(none yet)").setEnabled(False)

    def _connect_review(self) -> None:
        a = self.actions
        a["open_campaign"].triggered.connect(lambda: self.campaigns.open())
        a["next_pair"].triggered.connect(self.campaigns.next)
        a["prev_pair"].triggered.connect(self.campaigns.previous)
        a["accept_next"].triggered.connect(self.accept_and_next)
        a["zoom_clique"].triggered.connect(self.zoom_to_clique)
        self.segmentation_editor = editor = SegmentationEditor(self.session, self.views, self)
        modes = {"split_mode": "split", "paint_wall_mode": "paint_wall", "erase_wall_mode": "erase_wall"}
        for action_id, mode in modes.items():
            a[action_id].toggled.connect(lambda on, mode=mode: self._stroke_mode_toggled(mode, on))
        editor.mode_changed.connect(lambda mode: [a[i].setChecked(modes[i] == mode) for i in modes])
        a["clear_selection"].triggered.connect(lambda: editor.set_mode(""))
        a["merge_regions"].triggered.connect(editor.merge_selected)
        editor.message.connect(lambda text: self.statusBar().showMessage(text, 4000))
        self.navigation = NavigationController(self, editor)

    def _stroke_mode_toggled(self, mode: str, on: bool) -> None:
        editor = self.segmentation_editor
        if on:
            editor.set_mode(mode)
        elif editor.mode == mode:
            editor.set_mode("")

    def accept_and_next(self) -> None:
        """Accept the selected clique, select the next one to review and zoom to it."""
        if self.edits.accept_next() is not None:
            self.zoom_to_clique()

    def zoom_to_clique(self) -> None:
        clique_id = self.session.selected_clique
        if clique_id is None:
            return
        clique = self.session.clique(clique_id)
        for side, view in self.views.items():
            if not view.zoom_to_regions(getattr(clique, f"{side}_regions")):
                view.fit_to_window()

    def _fit_to_screen(self) -> None:
        """First run: most of the screen, never more (1366x768 at a 1.5 scale factor included)."""
        screen = self.screen() or QApplication.primaryScreen()
        if screen is None:
            self.resize(1280, 720)
            return
        available = screen.availableGeometry()
        self.resize(min(1600, int(available.width() * 0.92)), min(980, int(available.height() * 0.9)))

    def _size_panel_column(self) -> None:
        """A first start: the right column of panels takes a share of the window as shown, at least
        what its panels need (the maps get the rest of a laptop screen) and no more than they use."""
        needed = max(self.docks[name].minimumSizeHint().width() for name in ("segmentation", "matching"))
        width = max(needed, min(_PANEL_COLUMN_MAX, round(self.width() * _PANEL_COLUMN_SHARE)))
        self.resizeDocks([self.docks["matching"]], [width], Qt.Orientation.Horizontal)

    def _zoom_changed(self, side: str, factor: float) -> None:
        self.status.show_zoom(factor)
        if self.actions["link_zoom"].isChecked():
            other = self.views[SIDES[1 - SIDES.index(side)]]
            other.set_zoom(factor)  # set_zoom is a no-op at an equal factor, so no ping-pong

    def _zoom_all(self, step: float) -> None:
        for view in self.views.values():
            view.set_zoom(view.zoom_factor() * step)

    def fit_views(self) -> None:
        for view in self.views.values():
            view.fit_to_window()

    def _update_ready(self) -> None:
        ready = all(self.session.segmentation(side) is not None for side in SIDES) and not self.jobs.busy
        self.matching_panel.set_ready(ready)
        self.actions["match"].setEnabled(ready)
        self.actions["match_runner_up"].setEnabled(ready and self.matching_panel.runner_up_offered())
        self.actions["compare_readings"].setEnabled(ready and self.matching_panel.readings_offered())
        for side, box in self.segmentation_panel.boxes.items():
            box.segment_button.setEnabled(self.session.map(side) is not None and not self.jobs.busy)

    def _digest_of(self, side: str) -> str | None:
        loaded = self.session.map(side)
        return None if loaded is None else loaded.sha256

    def _forget_settings_of_another_map(self, side: str) -> None:
        # The orientation, input kind and scale belong to the maps open (see model.pair_settings):
        # another sketch (the next pair of a campaign, say) is matched with them unknown, not told
        # the last pair's. The same file opened again keeps them, and so does the canvas's drawing
        # used again after an edit (no file digest).
        forget = self._identities.settings_to_forget(side, self._digest_of(side))
        panel = self.matching_panel
        if "orientation" in forget:
            panel.set_orientation(SketchOrientation())
            # The file's record of how its match read the sketch read another sketch.
            self._record_reads_this_sketch = False
            self._show_match_summary()
        if "input_kind" in forget:
            panel.set_input_kind(None)
        if "scale" in forget:
            panel.set_scale(None)

    def _use_recorded_settings(self, correspondences) -> None:
        # A file opened again is matched again with the input kind and scale its cliques were made with.
        settings = recorded_settings(correspondences.extra.get("matcher"))
        if settings:
            self.matching_panel.set_input_kind(settings["input_kind"])
            self.matching_panel.set_scale(settings["scale"])
        # Its record reads its own sketch (opening it may have put another's away first).
        self._record_reads_this_sketch = True
        self._show_match_summary()

    def _show_match_summary(self) -> None:
        automatic = sum(1 for clique in self.session.correspondences.cliques if clique.source == "auto")
        if self.session.last_match is not None:
            self._record_reads_this_sketch = True  # the record is this match's
        record = self.session.correspondences.extra.get("matcher") if self._record_reads_this_sketch else None
        self.matching_panel.show_result(self.session.last_match, automatic_cliques=automatic, record=record)

    def _show_summary(self, side: str) -> None:
        segmentation = self.session.segmentation(side)
        if segmentation is None:
            text = "no segmentation"
        else:
            text = f"{counted(segmentation.n_regions, 'region')} ({segmentation.method})"
            reason = self.session.no_region_reason(side)
            if reason is not None:
                text += f": {reason}"
        self.segmentation_panel.boxes[side].set_summary(text)

    def _show_map_title(self, side: str) -> None:
        map_ = self.session.map(side)
        text = (
            side.capitalize()
            if map_ is None
            # Width x height, as image tools say it (the status bar gives pixels as (row, col)).
            else f"{side.capitalize()}: {_map_name(map_)}  ({map_.shape[1]} × {map_.shape[0]} px)"
        )
        self.view_titles[side].setText(text)
        self._update_ready()

    def show_shortcuts(self) -> ShortcutSheet:
        sheet = ShortcutSheet(self)
        sheet.open()
        return sheet

    # ---- inputs and closing ----------------------------------------------------------------------
    def open_inputs(
        self, sketch=None, metric=None, correspondences=None, *, example: bool = False, wait: bool = False
    ) -> bool:
        """Open maps and/or correspondences given on the command line (see ``WindowTools``)."""
        return self.tools.open_inputs(sketch, metric, correspondences, example=example, wait=wait)

    def discard_and_close(self) -> None:
        """Close without asking about unsaved changes (scripted runs)."""
        self._discard_on_close = True
        self.close()

    def showEvent(self, event) -> None:
        super().showEvent(event)
        if not self._shown:
            # Qt's leftovers from tabifying the docks while hidden (dock_tabs). Only now: a later
            # show can come before a new tab bar is laid out, which would look like a leftover.
            self._shown = True
            if not self._layout_restored:
                self._size_panel_column()
            hide_stray_tab_bars(self)

    def closeEvent(self, event) -> None:
        if not getattr(self, "_discard_on_close", False):
            # Drawing windows first: each asks about a drawing neither saved nor used.
            if not all(sketch.close() for sketch in self.tools.sketch_windows if sketch.isVisible()):
                event.ignore()
                return
            if self.campaigns.campaign is not None and not self.campaigns.save_current():
                event.ignore()
                return
            if not self.documents.confirm_discard("closing"):
                event.ignore()
                return
        self.preferences.save_window(self, {name: self.actions[name].isChecked() for name in _TOGGLE_DEFAULTS})
        self.jobs.cancel()
        self.jobs.runner.shutdown()
        self.session.read_ahead.close()
        self.documents.close_document()
        event.accept()


def _map_name(map_) -> str:
    # A map with no file was drawn in the app; it gets one beside the document when that is saved.
    return map_.name if map_.path is not None else "drawn, not saved yet"
