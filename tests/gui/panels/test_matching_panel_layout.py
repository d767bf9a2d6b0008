"""The matching panel's layout: Match first, every orientation button explained, no setting as wide as its
longest choice."""

from __future__ import annotations

from PySide6.QtWidgets import QComboBox

from ursim_gui.panels.matching_panel import MatchingPanel


def test_match_comes_before_the_orientation_and_the_settings(qtbot):
    panel = MatchingPanel()
    qtbot.addWidget(panel)
    panel.show()
    qtbot.waitExposed(panel)

    def top(widget) -> int:
        return widget.mapTo(panel, widget.rect().topLeft()).y()

    assert top(panel.match_button) < top(panel.turn_left) < top(panel.summary) < top(panel.variant)


def test_every_orientation_control_has_a_tooltip(qtbot):
    """⟳ 90° and mirror had none (⟲ 90° had one)."""
    panel = MatchingPanel()
    qtbot.addWidget(panel)
    for widget in (panel.turn_left, panel.turn_right, panel.angle, panel.mirror, panel.unknown):
        assert widget.toolTip(), widget.objectName()
    assert panel.turn_left.toolTip() != panel.turn_right.toolTip()


def test_the_longest_choice_does_not_widen_the_panel(qtbot):
    """The settings lists were as wide as their longest choice: the panel needed 562 px, and so did the
    whole right column of the window."""
    panel = MatchingPanel()
    qtbot.addWidget(panel)
    for combo in panel.findChildren(QComboBox):
        combo.setCurrentIndex(max(range(combo.count()), key=lambda index: len(combo.itemText(index))))
    panel.show()
    assert panel.minimumSizeHint().width() <= 400


def test_turn_and_mirror_set_the_one_orientation(qtbot):
    panel = MatchingPanel()
    qtbot.addWidget(panel)
    told = []
    panel.orientation_changed.connect(told.append)
    panel.turn(90.0)
    panel.set_mirrored(True)
    panel.set_mirrored(True)  # no change, no signal
    assert [(o.angle, o.mirrored) for o in told] == [(90.0, False), (90.0, True)]
    assert panel.mirror.isChecked() and panel.angle.value() == 90.0
