"""Binds the session to the two map views: model signals -> drawing, view input -> model calls.

The binding holds no annotation state. It re-reads the session when it signals a change
and draws with the pure helpers of :mod:`ursim_gui.model.view_state`; clicks become
``session.select`` calls. Hover is purely visual: it only re-draws the cheap highlight
layer of the other view.
"""

from __future__ import annotations

import functools

import numpy as np
from PySide6.QtGui import QColor

from ursim_core.matching.template import free_box
from ursim_gui.model.view_state import eval_badges, first_regions, side_colour_table

__all__ = ["ViewBinding", "SIDES"]

SIDES = ("sketch", "metric")
_BADGE_COLOURS = {"TP": QColor(30, 140, 60), "FP": QColor(200, 40, 40), "FN": QColor(200, 120, 0)}


class ViewBinding:
    """Keeps ``views[side]`` and the connector overlay in step with ``session``.

    Parameters
    ----------
    session : AnnotationSession
    views : dict of side -> MapView
    connectors : ConnectorOverlay
    """

    def __init__(self, session, views: dict, connectors):
        self.session = session
        self.views = views
        self.connectors = connectors
        # Colours depend on the clique id only; caching saves an HSV conversion per
        # clique and side on every edit.
        self._colour_of = functools.lru_cache(maxsize=4096)(session.color_of_clique)
        self._hovered: tuple[str, int] = ("sketch", 0)
        # The laid sketch of the last match, made once per match and segmentations (about 15 ms).
        self._laid_visible = False
        # The sketch's colour table as last painted: the laid sketch is drawn in it too.
        self._sketch_colours: np.ndarray | None = None
        session.map_changed.connect(self._map_changed)
        session.segmentation_changed.connect(self._segmentation_changed)
        session.correspondences_changed.connect(self._correspondences_changed)
        session.selection_changed.connect(self._selection_changed)
        session.reference_changed.connect(self._badges_changed)
        for side, view in views.items():
            view.region_hovered.connect(lambda region, side=side: self.hover(side, region))
            view.region_clicked.connect(lambda region, additive, side=side: self.click(side, region, additive))
        for side in SIDES:
            self._map_changed(side)

    # ---- view input -> model -------------------------------------------------------------
    def click(self, side: str, region: int, additive: bool) -> None:
        """A click on ``region`` (0 = background).

        Ctrl-click adds the region to the selection (keeping the selected clique, so L
        adds to it). A plain click on a matched region selects its clique (both sides
        and the table row); on an unmatched one it selects the region on its side,
        keeping the other side's selection, so click-click-L links a pair. A plain
        click on the background clears the selection.
        """
        if region <= 0:
            if not additive:
                self.session.clear_selection()
            return
        if additive:
            self.session.select(side, [region], add=True)
            return
        cliques = self.session.clique_of(side, region)
        if cliques:
            self.session.select_clique(cliques[0], focus=(side, region))
        else:
            self.session.select(side, [region])

    def hover(self, side: str, region: int) -> None:
        """Highlight the partners of ``region`` in the other view (nothing for 0)."""
        self._hovered = (side, region)
        other = SIDES[1 - SIDES.index(side)]
        self.views[other].set_highlight(self.session.partners(side, region) if region > 0 else ())

    # ---- model -> views ------------------------------------------------------------------------
    def _map_changed(self, side: str) -> None:
        map_ = self.session.map(side)
        view = self.views[side]
        if map_ is None:
            view.set_image(None)
            return
        grey = map_.image if map_.image is not None else np.where(map_.free, 255, 0).astype(np.uint8)
        view.set_image(grey, drawn=free_box(map_.free))
        self._segmentation_changed(side)

    def _segmentation_changed(self, side: str) -> None:
        segmentation = self.session.segmentation(side)
        view = self.views[side]
        if segmentation is None:
            view.set_segmentation(None, None)
        else:
            view.set_segmentation(segmentation.labels, segmentation.graph)
        self._paint(side)
        self._badges_changed()
        self._update_links()
        self._show_laid()

    def _correspondences_changed(self, *_args) -> None:
        for side in SIDES:
            self._paint(side)
        self._badges_changed()
        self._update_links()
        self._show_laid()
        self.hover(*self._hovered)  # the hovered region's partners may have changed

    def _selection_changed(self, *_args) -> None:
        selection = self.session.selection
        for side in SIDES:
            self.views[side].set_selection(selection.get(side, ()))

    def _badges_changed(self, *_args) -> None:
        for side in SIDES:
            reference = self.session.reference or []
            missed = [reference[index] for index in self.session.missed_reference()]
            badges = eval_badges(self.session.correspondences, side, self.session.clique_status, missed)
            self.views[side].set_badges({region: (mark, _BADGE_COLOURS[mark]) for region, mark in badges.items()})

    def _paint(self, side: str) -> None:
        """Recolour one side and re-mark its anchors and selection."""
        segmentation = self.session.segmentation(side)
        view = self.views[side]
        if segmentation is not None:
            max_label = max(segmentation.graph.nodes, default=0)
            table = side_colour_table(
                self.session.correspondences, side, segmentation.labels, self._colour_of, max_label=max_label
            )
            view.set_region_colours(table)
            if side == "sketch":
                self._sketch_colours = table
            index = SIDES.index(side)
            view.set_anchors({pair[index] for pair in self.session.anchors})
            view.set_selection(self.session.selection.get(side, ()))

    def set_laid_visible(self, visible: bool) -> None:
        """Show or hide the sketch laid on the metric map by the last match (View > Laid sketch)."""
        self._laid_visible = bool(visible)
        self._show_laid()

    def _show_laid(self) -> None:
        view = self.views["metric"]
        laid = self.session.laid_sketch() if self._laid_visible else None
        if laid is None or self._sketch_colours is None:
            view.set_laid_sketch(None)
            return
        # In the sketch's clique colours as painted (each laid region shows whose partner it
        # became), darkened: over the metric map's own overlay in the same colours, plain ones
        # would vanish.
        table = self._sketch_colours.copy()
        table[:, :3] = table[:, :3] * 0.45
        view.set_laid_sketch(laid, table)

    def _update_links(self) -> None:
        self.connectors.set_links(
            (sketch, metric, self._colour_of(clique_id))
            for clique_id, sketch, metric in first_regions(self.session.correspondences)
        )
