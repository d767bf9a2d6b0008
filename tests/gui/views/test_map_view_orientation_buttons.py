"""The sketch view's own turn and mirror buttons: they tell the matcher through the matching panel, and
the panel's buttons show on them (one orientation, held by the panel)."""

from __future__ import annotations

import dataclasses

from PySide6.QtCore import Qt

from ursim_core.matching import MatchConfig
from ursim_gui.views.map_view import MapView

_TOLD = "orientation" in {field.name for field in dataclasses.fields(MatchConfig)}


def press(qtbot, view: MapView, key: str) -> None:
    """Click the sketch view's button ``key`` ('left', 'right' or 'mirror') as a user does."""
    button = view.orientation_bar.widgetForAction(view.orientation_actions[key])
    assert button.isVisible() and button.toolTip()
    qtbot.mouseClick(button, Qt.MouseButton.LeftButton)


def test_the_views_buttons_turn_the_sketch_and_tell_the_matcher(window, qtbot):
    panel, sketch = window.matching_panel, window.views["sketch"]
    mirror = sketch.orientation_actions["mirror"]
    press(qtbot, sketch, "left")
    assert panel.orientation.angle == 90.0 and panel.angle.value() == 90.0
    assert sketch.orientation == (90.0, False)
    press(qtbot, sketch, "mirror")
    assert panel.orientation.mirrored and panel.mirror.isChecked() and mirror.isChecked()
    assert sketch.orientation == (90.0, True)
    press(qtbot, sketch, "right")
    press(qtbot, sketch, "right")
    assert panel.orientation.angle == 270.0 and sketch.orientation == (270.0, True)
    if _TOLD:
        config = panel.config()
        assert (config.orientation, config.mirrored) == (270.0, True)


def test_the_panels_buttons_show_on_the_views(window, qtbot):
    panel, sketch = window.matching_panel, window.views["sketch"]
    mirror = sketch.orientation_actions["mirror"]
    panel.mirror.click()
    assert mirror.isChecked() and sketch.orientation == (0.0, True)
    press(qtbot, sketch, "mirror")  # the view's button takes the mirror off again
    assert not panel.mirror.isChecked() and not mirror.isChecked() and not panel.orientation.mirrored
    panel.turn_right.click()
    panel.mirror.click()
    assert sketch.orientation == (270.0, True) and mirror.isChecked()
    panel.unknown.click()
    assert sketch.orientation == (0.0, False) and not mirror.isChecked() and not panel.orientation.known
    if _TOLD:
        assert panel.config().orientation == "any"


def test_only_the_sketch_view_has_them_and_only_with_a_map(window, qtbot):
    assert window.views["metric"].orientation_bar is None
    bar = window.views["sketch"].orientation_bar
    assert bar.isVisible()
    assert all(action.toolTip() for action in window.views["sketch"].orientation_actions.values())
    empty = MapView("sketch")
    qtbot.addWidget(empty)
    empty.show()
    assert not empty.orientation_bar.isVisible()  # nothing to turn


def test_a_view_alone_only_asks_and_its_buttons_stay_in_the_corner(qtbot, grey3):
    view = MapView("sketch")
    qtbot.addWidget(view)
    view.resize(500, 300)
    view.show()
    qtbot.waitExposed(view)
    view.set_image(grey3)
    turns, mirrors = [], []
    view.turn_requested.connect(turns.append)
    view.mirror_requested.connect(mirrors.append)
    press(qtbot, view, "left")
    press(qtbot, view, "right")
    press(qtbot, view, "mirror")
    assert turns == [90.0, -90.0] and mirrors == [True]
    # Nobody turned it: the view and its mirror button still show the orientation it was given.
    assert view.orientation == (0.0, False) and not view.orientation_actions["mirror"].isChecked()
    corner = view.orientation_bar.pos()
    view.set_zoom(8.0)
    view.horizontalScrollBar().setValue(view.horizontalScrollBar().maximum())
    view.verticalScrollBar().setValue(view.verticalScrollBar().maximum())
    assert view.orientation_bar.pos() == corner  # not scrolled away with the map
    assert view.viewport().geometry().contains(view.orientation_bar.geometry())
