"""Feature 7: select with clicks, then L / U / Delete / A / R, undo and redo with the
keyboard; F1 opens the shortcut sheet listing them."""

from __future__ import annotations

from conftest import region_point
from PySide6.QtCore import Qt
from PySide6.QtGui import QKeySequence
from PySide6.QtWidgets import QApplication

from ursim_gui.window.shortcuts import SHORTCUTS, ShortcutSheet


def click(qtbot, view, region, modifier=Qt.KeyboardModifier.NoModifier):
    qtbot.mouseClick(view.viewport(), Qt.MouseButton.LeftButton, modifier, region_point(view, region))


def key(qtbot, window, name, modifier=Qt.KeyboardModifier.NoModifier):
    qtbot.keyClick(window.views["sketch"], name, modifier)


def test_link_unlink_delete_accept_reject_undo_redo_with_keys(window, qtbot):
    session = window.session
    sketch, metric = window.views["sketch"], window.views["metric"]
    window.views["sketch"].setFocus()

    click(qtbot, sketch, 1)
    click(qtbot, metric, 2)
    assert session.selection == {"sketch": frozenset({1}), "metric": frozenset({2})}
    key(qtbot, window, Qt.Key.Key_L)
    (clique,) = session.correspondences.cliques
    assert (clique.sketch_regions, clique.metric_regions, clique.source) == ((1,), (2,), "manual")
    assert window.table.model.rowCount() == 1

    click(qtbot, sketch, 1)  # selects the clique
    assert session.selected_clique == clique.id
    click(qtbot, metric, 3, Qt.KeyboardModifier.ControlModifier)  # add a region to it
    key(qtbot, window, Qt.Key.Key_L)
    assert session.clique(clique.id).metric_regions == (2, 3)

    key(qtbot, window, Qt.Key.Key_R)
    assert session.clique(clique.id).status == "rejected"
    assert "rejected" in window.table.model.data(window.table.model.index(0, 5))
    key(qtbot, window, Qt.Key.Key_Y)
    assert session.clique(clique.id).status == "accepted"

    session.select("metric", [3])
    key(qtbot, window, Qt.Key.Key_U)
    assert session.clique(clique.id).metric_regions == (2,)

    session.select_clique(clique.id)
    key(qtbot, window, Qt.Key.Key_Delete)
    assert session.correspondences.cliques == ()

    key(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert len(session.correspondences.cliques) == 1
    key(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier | Qt.KeyboardModifier.ShiftModifier)
    assert session.correspondences.cliques == ()
    key(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    key(qtbot, window, Qt.Key.Key_Z, Qt.KeyboardModifier.ControlModifier)
    assert session.clique(clique.id).metric_regions == (2, 3)
    key(qtbot, window, Qt.Key.Key_Y, Qt.KeyboardModifier.ControlModifier)
    assert session.clique(clique.id).metric_regions == (2,)
    assert window.actions["undo"].isEnabled() and window.actions["undo"].text().startswith("&Undo Unlink")


def test_escape_clears_and_keys_without_a_selection_do_nothing(window, qtbot):
    session = window.session
    click(qtbot, window.views["sketch"], 2)
    key(qtbot, window, Qt.Key.Key_Escape)
    assert session.selection == {"sketch": frozenset(), "metric": frozenset()}
    for name in (Qt.Key.Key_L, Qt.Key.Key_Y, Qt.Key.Key_A, Qt.Key.Key_D, Qt.Key.Key_Delete):
        key(qtbot, window, name)
    assert session.correspondences.cliques == () and not session.can_undo


def test_f1_opens_the_shortcut_sheet(window, qtbot):
    key(qtbot, window, Qt.Key.Key_F1)
    sheets = [w for w in QApplication.topLevelWidgets() if isinstance(w, ShortcutSheet) and w.isVisible()]
    if not sheets:
        sheets = [w for w in window.findChildren(ShortcutSheet) if w.isVisible()]
    assert sheets
    keys = sheets[0].key_texts()
    native = QKeySequence.SequenceFormat.NativeText
    for spec in SHORTCUTS:
        for sequence in spec.keys:
            assert any(QKeySequence(sequence).toString(native) in text for text in keys), spec.id
    assert "Ctrl+Click" in keys
    sheets[0].close()
