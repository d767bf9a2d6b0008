"""Edit commands from the keyboard: link, unlink, delete, accept, reject, relink, accept and next, undo and redo."""

from __future__ import annotations

from conftest import click, key, link_by_clicks, new_window, region_point
from PySide6.QtCore import Qt


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


def test_unlink_touches_only_the_clicked_region_of_the_selected_clique(window, qtbot):
    session = window.session
    link_by_clicks(qtbot, window, 1, 1)
    link_by_clicks(qtbot, window, 2, 1)  # metric 1 is in two cliques
    first, second = session.correspondences.cliques
    steps = len(session.history)
    undo_before = session.undo_text

    click(qtbot, window.views["sketch"], 1)  # selects the first clique
    assert session.selected_clique == first.id
    key(qtbot, window, Qt.Key.Key_U)

    after_first, after_second = session.correspondences.cliques
    assert after_first.sketch_regions == () and after_first.metric_regions == (1,)
    assert after_second == second  # the other clique keeps metric region 1
    assert len(session.history) == steps + 1
    session.undo()  # one step undoes the whole unlink
    assert session.correspondences.cliques == (first, second) and session.undo_text == undo_before


def test_link_after_a_table_selection_uses_only_clicked_regions(window, qtbot):
    session = window.session
    link_by_clicks(qtbot, window, 1, 1)
    session.clear_selection()
    window.table.view.selectRow(0)  # the clique 1 <-> 1, picked in the table
    assert session.selected_clique == session.correspondences.cliques[0].id
    click(qtbot, window.views["sketch"], 3)  # an unmatched sketch region
    key(qtbot, window, Qt.Key.Key_L)
    new = session.correspondences.cliques[-1]
    assert new.sketch_regions == (3,) and new.metric_regions == ()


def test_review_fixes_a_wrong_match_in_three_actions(plain_campaign, qtbot, tmp_path):
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=tmp_path / "out")
    session = window.session
    # Make one clique wrong (sketch a <-> metric b, b != the metric partner it should have).
    (first, *_rest) = session.correspondences.cliques
    sketch_region = first.sketch_regions[0]
    wrong = next(c.metric_regions[0] for c in session.correspondences.cliques if c.id != first.id)
    session.relink(first.id, "metric", [wrong])
    session.set_status(first.id, "pending")
    right = first.metric_regions[0]
    # 1: click the sketch region (selects its clique); 2: Ctrl+click the right metric region; 3: E.
    sketch_view, metric_view = window.views["sketch"], window.views["metric"]
    qtbot.mouseClick(sketch_view.viewport(), Qt.MouseButton.LeftButton, pos=region_point(sketch_view, sketch_region))
    qtbot.mouseClick(
        metric_view.viewport(),
        Qt.MouseButton.LeftButton,
        Qt.KeyboardModifier.ControlModifier,
        region_point(metric_view, right),
    )
    qtbot.keyClick(sketch_view, Qt.Key.Key_E)
    fixed = session.clique(first.id)
    assert fixed.metric_regions == (right,) and fixed.status == "accepted" and fixed.source == "manual"


def test_accept_and_next_and_zoom_to_clique(plain_campaign, qtbot, tmp_path):
    window = new_window(qtbot, tmp_path / "userdata")
    with qtbot.waitSignal(window.campaigns.pair_ready, timeout=180_000):
        window.campaigns.open(plain_campaign, output_dir=tmp_path / "out")
    session = window.session
    cliques = session.correspondences.cliques
    assert len(cliques) >= 2
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Space)  # nothing selected: selects the first to review
    assert session.selected_clique == cliques[0].id
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Space)  # accept it, go to the next
    assert session.clique(cliques[0].id).status == "accepted" and session.selected_clique == cliques[1].id
    window.fit_views()
    fitted = window.views["sketch"].zoom_factor()
    qtbot.keyClick(window.views["sketch"], Qt.Key.Key_Z)
    assert window.views["sketch"].zoom_factor() > fitted
