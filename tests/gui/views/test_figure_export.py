"""The exported PNG figure: both views with a legend, region ids drawn, a failed export said."""

from __future__ import annotations

from pathlib import Path

from conftest import answer_file_dialogs, error_boxes
from PySide6.QtGui import QImage

from ursim_gui.views import file_dialogs


def test_export_figure_writes_a_png_with_a_legend(window, tmp_path, monkeypatch):
    window.session.link([1], [1])
    window.session.link([2], [3])
    window.actions["connectors"].setChecked(True)
    window.session.select_clique(window.session.correspondences.cliques[0].id)
    target = tmp_path / "figure.png"
    monkeypatch.setattr(file_dialogs, "ask_save_path", lambda *a, **k: Path(str(target)))
    window.actions["export_figure"].trigger()
    image = QImage(str(target))
    assert not image.isNull() and image.width() > 600 and image.height() > 600
    # The sketch's room 1 is drawn in clique 1's colour somewhere in the left half.
    colour = window.session.color_of_clique(1)
    found = any(
        abs(image.pixelColor(x, y).red() - colour[0]) < 40
        and abs(image.pixelColor(x, y).green() - colour[1]) < 40
        and abs(image.pixelColor(x, y).blue() - colour[2]) < 40
        for x in range(0, image.width() // 2, 7)
        for y in range(0, image.height() // 2, 7)
    )
    assert found
    assert window.views["sketch"].marked_regions("selection") == {1}  # hidden only while rendering
    assert all(item.isVisible() for item in window.views["sketch"].layers._marks["selection"])


def test_failed_figure_export_shows_an_error(window, tmp_path):
    assert not window.tools.export_figure(tmp_path / "nope" / "figure.png")
    assert error_boxes(window)


def test_exported_figure_draws_region_ids(window, tmp_path, monkeypatch):
    assert not window.actions["region_ids"].isChecked()
    seen = {}
    for side, view in window.views.items():
        scene = view.scene()
        original = scene.render

        def spy(*args, side=side, view=view, original=original, **kwargs):
            seen[side] = view.layers.visible_ids()
            return original(*args, **kwargs)

        monkeypatch.setattr(scene, "render", spy)
    answer_file_dialogs(monkeypatch, tmp_path / "figure.png")
    window.actions["export_figure"].trigger()
    assert (tmp_path / "figure.png").is_file()
    assert seen == {"sketch": {1, 2, 3}, "metric": {1, 2, 3}}
    assert window.views["sketch"].layers.visible_ids() == set()  # the view is as it was
