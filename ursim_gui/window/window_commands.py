"""Main-window commands that open a tool or dialog: new sketch, label image, figure, inputs.

Split from :mod:`ursim_gui.window.main_window` so that module stays pure composition.
"""

from __future__ import annotations

import logging
from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QDialog

from ursim_core.errors import UrsimError
from ursim_gui.model.example import example_inputs
from ursim_gui.tools.sketch_canvas import SketchSizeDialog, SketchWindow
from ursim_gui.views import file_dialogs
from ursim_gui.views.figure_export import export_figure
from ursim_gui.views.readings_dialog import ReadingsDialog, drawn_part
from ursim_gui.window import dialogs

__all__ = ["WindowTools"]

_log = logging.getLogger(__name__)


class WindowTools:
    """Commands of ``window`` (a :class:`~ursim_gui.window.main_window.MainWindow`)."""

    def __init__(self, window):
        self.window = window
        self.session = window.session
        self.sketch_windows: list[SketchWindow] = []

    # ---- sketching ---------------------------------------------------------------------
    def new_sketch(self, size: tuple[int, int] | None = None) -> SketchWindow | None:
        """Open a drawing window; asks for the size unless ``size`` (rows, cols) is given."""
        if size is None:
            dialog = SketchSizeDialog(self.window)
            if dialog.exec() != QDialog.DialogCode.Accepted:
                return None
            size = dialog.size_rc()
        sketch = SketchWindow(*size, parent=self.window)
        sketch.use_as_sketch.connect(self.use_as_sketch)
        self.sketch_windows.append(sketch)
        sketch.show()
        return sketch

    def use_as_sketch(self, image, saved_path=None) -> bool:
        """The drawing window's image becomes the sketch, by the rule of opening a map: another
        sketch than the document's starts a new document, after asking about unsaved changes.
        A drawing still as saved is opened from its PNG; one never saved has no file until the
        document is saved, which writes it beside the document."""
        from ursim_core.io.maps import map_from_array

        if saved_path is not None:
            return self.window.documents.open_map("sketch", saved_path)
        try:
            map_ = map_from_array(image)
        except (UrsimError, ValueError) as error:
            dialogs.show_error(self.window, "Cannot use the sketch", str(error))
            return False
        return self.window.documents.show_map("sketch", map_, "using the drawn sketch")

    # ---- orientation ---------------------------------------------------------------------
    def compare_readings(self) -> ReadingsDialog | None:
        """Show the readings the last match ranked side by side (:class:`ReadingsDialog`); the one
        chosen is told to the matcher, which matches again. None when no readings are offered."""
        panel = self.window.matching_panel
        if not panel.readings_offered():
            return None
        from ursim_core.matching.template import free_box

        # Each map's drawn part: a sketch drawn small on a large sheet would be a speck in its tile.
        sketch, metric = (
            drawn_part(self.window.views[side].map_image(), free_box(self.session.map(side).free))
            for side in ("sketch", "metric")
        )
        dialog = ReadingsDialog(sketch, metric, panel.readings, panel.answer_reading, self.window)
        dialog.reading_chosen.connect(panel.match_reading)
        dialog.setAttribute(Qt.WidgetAttribute.WA_DeleteOnClose)
        dialog.open()
        return dialog

    # ---- segmentation input --------------------------------------------------------------------
    def load_label_image(self, side: str, path: Path | None = None) -> bool:
        """Use a label image (0 = no region) as ``side``'s segmentation instead of segmenting."""
        from ursim_core.segmentation import load_label_image

        map_ = self.session.map(side)
        if map_ is None:
            dialogs.show_error(self.window, "No map", f"Open the {side} map before its label image.")
            return False
        if path is None:
            path = file_dialogs.ask_open_path(
                self.window, f"Load {side} label image", "Label images (*.png *.tif *.tiff)"
            )
            if path is None:
                return False
        try:
            self.session.set_segmentation(side, load_label_image(path, shape=map_.shape))
        except (UrsimError, OSError) as error:
            dialogs.show_error(self.window, "Cannot load the label image", str(error))
            return False
        return True

    # ---- figure and status --------------------------------------------------------------------
    def export_figure(self, path: Path | None = None) -> bool:
        if path is None:
            path = file_dialogs.ask_save_path(self.window, "Export figure", "figure.png", "PNG image (*.png)")
            if path is None:
                return False
        views = self.window.views
        try:
            export_figure(
                path,
                views["sketch"],
                views["metric"],
                self.session,
                connectors=self.window.actions["connectors"].isChecked(),
            )
        except OSError as error:
            dialogs.show_error(self.window, "Export failed", str(error))
            return False
        self.window.statusBar().showMessage(f"Figure written to {path}", 4000)
        return True

    def show_cursor(self, side: str, row: int, col: int) -> None:
        map_ = self.session.map(side)
        world = None
        if row >= 0 and map_ is not None and map_.resolution is not None and map_.origin is not None:
            from ursim_core.io.maps import pixel_to_world

            x, y = pixel_to_world(map_, row, col)
            world = (float(x), float(y))
        view = self.window.views[side]
        region = view.region_at(row, col) if row >= 0 else 0
        self.window.status.show_cursor(side, row, col, world, region)
        view.viewport().setToolTip(self.region_tooltip(side, region))

    def region_tooltip(self, side: str, region: int) -> str:
        """``'Region 4 · clique 2 “kitchen”'`` for the map's hover tooltip ('' off the regions)."""
        from ursim_core.correspondences.exporters import clique_label

        if region <= 0:
            return ""
        parts = [f"Region {region}"]
        for clique_id in self.session.clique_of(side, region):
            label = clique_label(self.session.clique(clique_id))
            parts.append(f"clique {clique_id}" + (f" “{label}”" if label else ""))
        return " · ".join(parts)

    # ---- command-line inputs ------------------------------------------------------------------------
    def open_inputs(
        self, sketch=None, metric=None, correspondences=None, *, example: bool = False, wait: bool = False
    ) -> bool:
        """Open what the command line named; with ``example``, the bundled pair.

        Two maps are segmented with the default presets and matched (in the worker, or
        in this thread with ``wait``). With the example, its ground truth is loaded as
        the reference so the evaluation is live. Returns False when something failed.
        """
        docs, reference = self.window.documents, None
        if example:
            found = example_inputs()
            if found is None:
                _log.warning("the bundled example (resources/example) is missing; starting empty")
                return True
            sketch, metric, reference = found
        ok = True
        if correspondences is not None:
            ok = docs.open_correspondences(Path(correspondences))
        if sketch is not None and metric is not None:
            ok = docs.open_map("sketch", Path(sketch)) and docs.open_map("metric", Path(metric)) and ok
            if ok:
                ok = self.segment_and_match(wait=wait)
        if reference is not None and ok:
            ok = docs.load_reference(reference)
        return ok

    def segment_and_match(self, *, wait: bool = False) -> bool:
        """Segment both maps with their panel settings, then match.

        With ``wait`` the jobs run in this thread (False when one failed); else they are
        queued in the worker and True is returned at once.
        """
        from ursim_gui.jobs.controller import MatchRequest
        from ursim_gui.model.jobs import SegmentJob

        jobs, panel = self.window.jobs, self.window.segmentation_panel
        config = self.window.matching_panel.config()
        if not wait:
            for side in ("sketch", "metric"):
                box = panel.boxes[side]
                jobs.segment(side, box.preset.currentText(), box.overrides(), method=box.method_name())
            jobs.match(config)
            return True
        for side in ("sketch", "metric"):
            box = panel.boxes[side]
            if not jobs.run_now(
                SegmentJob(
                    self.session.map(side),
                    box.preset.currentText(),
                    box.overrides(),
                    method=box.method_name(),
                    side=side,
                )
            ):
                return False
        self.session.match_config = config
        return jobs.run_now(MatchRequest(config))
