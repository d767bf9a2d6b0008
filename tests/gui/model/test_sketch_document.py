"""SketchDocument: the Qt-free drawing model behind File > New sketch."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_gui.model.sketch_document import INK, PAPER, SketchDocument


def test_pen_stroke_draws_and_undo_redo_are_exact():
    doc = SketchDocument(50, 80)
    blank = doc.image.copy()
    doc.begin(10, 10)
    doc.extend(10, 40)
    doc.end(10, 60)
    drawn = doc.image.copy()
    assert (drawn[10, 10:61] == INK).all()
    assert doc.can_undo and not doc.can_redo
    doc.undo()
    assert np.array_equal(doc.image, blank)
    doc.redo()
    assert np.array_equal(doc.image, drawn)


def test_shapes_are_redrawn_from_the_stroke_start():
    doc = SketchDocument(60, 60)
    doc.tool = "rectangle"
    doc.width = 1
    doc.begin(5, 5)
    doc.extend(50, 50)  # preview of a large rectangle...
    doc.end(20, 20)  # ...replaced by the final one
    assert doc.image[5, 5] == INK and doc.image[20, 20] == INK
    assert doc.image[50, 50] == PAPER
    assert doc.image[12, 12] == PAPER  # outline only
    doc.tool = "wall"
    doc.begin(40, 0)
    doc.end(40, 59)
    assert (doc.image[40, :] == INK).all()


def test_eraser_and_clear():
    doc = SketchDocument(30, 30)
    doc.width = 5
    doc.begin(15, 0)
    doc.end(15, 29)
    doc.tool = "eraser"
    doc.begin(15, 10)
    doc.end(15, 20)
    assert doc.image[15, 15] == PAPER and doc.image[15, 2] == INK
    doc.clear()
    assert (doc.image == PAPER).all()
    doc.undo()
    assert doc.image[15, 2] == INK


def test_save_png_round_trips(tmp_path):
    doc = SketchDocument(20, 30)
    doc.begin(3, 3)
    doc.end(3, 20)
    path = tmp_path / "s.png"
    doc.save_png(path)
    assert np.array_equal(cv2.imread(str(path), cv2.IMREAD_UNCHANGED), doc.image)
    with pytest.raises(OSError):
        doc.save_png(tmp_path / "missing" / "s.png")


def test_too_small_canvas_is_refused():
    with pytest.raises(ValueError):
        SketchDocument(4, 100)


def test_map_image_keeps_open_drawings_and_fills_outside_closed_ones():
    from ursim_gui.model.sketch_document import INK, PAPER, SketchDocument

    doc = SketchDocument(30, 40)
    doc.image[15, 5:35] = INK  # one wall, no outline: nothing is outside
    assert (doc.map_image() == doc.image).all()
    doc.image[3, 3:37] = doc.image[26, 3:37] = INK  # now a closed outline
    doc.image[3:27, 3] = doc.image[3:27, 36] = INK
    drawn = doc.map_image()
    assert drawn[0, 0] == INK and drawn[29, 39] == INK
    assert drawn[8, 20] == PAPER and drawn[20, 20] == PAPER
    assert doc.image[0, 0] == PAPER, "the drawing itself is not changed"
