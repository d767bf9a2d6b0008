"""The readings dialog: the sketch turned as each ranked reading, one click to match in it."""

from __future__ import annotations

import numpy as np
from PySide6.QtCore import Qt
from PySide6.QtGui import QColor, QIcon, QImage

from ursim_gui.model.orientation import SketchOrientation
from ursim_gui.views.readings_dialog import ReadingsDialog, drawn_part, turned_picture

READINGS = [
    (SketchOrientation(0.0, False), 0.0),
    (SketchOrientation(180.0, True), 0.004),
    (SketchOrientation(90.0, False), 0.3),
]


def _marked_image() -> QImage:
    """A white 40 x 80 image with its top-left corner black: where a reading takes it shows."""
    image = QImage(80, 40, QImage.Format.Format_ARGB32)
    image.fill(QColor("white"))
    for row in range(10):
        for col in range(10):
            image.setPixelColor(col, row, QColor("black"))
    return image


def _pixels(pixmap) -> np.ndarray:
    image = pixmap.toImage().convertToFormat(QImage.Format.Format_ARGB32)
    buffer = np.frombuffer(image.constBits(), np.uint8).reshape(image.height(), image.bytesPerLine() // 4, 4)
    return buffer[:, : image.width()].copy()


def test_each_tile_shows_the_sketch_as_its_reading_turns_it(qapp):  # pixmaps need the app
    upright = _pixels(turned_picture(_marked_image(), SketchOrientation(0.0), side=80))
    assert upright.shape[:2] == (40, 80) and upright[2, 2, :3].max() < 50 and upright[2, 77, :3].min() > 200
    # Mirrored left-right, the dark corner goes to the top right; turned a half turn after the
    # mirror, to the bottom left.
    mirrored = _pixels(turned_picture(_marked_image(), SketchOrientation(0.0, True), side=80))
    assert mirrored[2, 77, :3].max() < 50 and mirrored[2, 2, :3].min() > 200
    half = _pixels(turned_picture(_marked_image(), SketchOrientation(180.0, True), side=80))
    assert half[37, 2, :3].max() < 50 and half[2, 77, :3].min() > 200
    # A quarter turn counter-clockwise stands the image up, its top-left corner at the bottom left.
    quarter = _pixels(turned_picture(_marked_image(), SketchOrientation(90.0), side=80))
    assert quarter.shape[:2] == (80, 40) and quarter[77, 2, :3].max() < 50
    # A free angle uncovers corners: transparent, not black.
    free = _pixels(turned_picture(_marked_image(), SketchOrientation(30.0), side=80))
    assert free[0, 0, 3] == 0 and free[free.shape[0] // 2, free.shape[1] // 2, 3] == 255
    assert turned_picture(QImage(), SketchOrientation(0.0)).isNull()


def test_a_sketch_drawn_small_on_a_large_sheet_fills_its_tile(qapp):
    sheet = QImage(400, 300, QImage.Format.Format_ARGB32)
    sheet.fill(QColor("black"))
    for row in range(100, 150):
        for col in range(200, 300):
            sheet.setPixelColor(col, row, QColor("white"))
    part = drawn_part(sheet, (100, 150, 200, 300))  # rows 100-149, columns 200-299: 2 px of margin
    assert (part.width(), part.height()) == (104, 54)
    tile = _pixels(turned_picture(part, SketchOrientation(0.0), side=104))
    assert tile[27, 52, :3].min() > 200 and tile[0, 0, :3].max() < 50  # the block fills it; the margin stays dark
    # Near the image's edge the margin stops at it; no box (no free space) is the whole image.
    corner = drawn_part(sheet, (0, 10, 390, 400))  # a margin of 1 px, cut at the top and the right
    assert (corner.width(), corner.height()) == (11, 11)
    assert drawn_part(sheet, None).size() == sheet.size()


def test_the_tiles_rank_the_readings_and_choosing_one_says_which(qtbot):
    dialog = ReadingsDialog(_marked_image(), _marked_image(), READINGS, shown=SketchOrientation(0.0, False))
    qtbot.addWidget(dialog)
    texts = [tile.text() for tile in dialog.tiles]
    assert texts == [
        "1. upright\nread by the matcher · shown now",
        "2. turned 180° counter-clockwise, mirrored\nranked 0.4% worse",
        "3. turned 90° counter-clockwise\nranked 30.0% worse",
    ]
    # The answer shown now cannot be asked for again; it keeps its picture, not greyed.
    assert [tile.isEnabled() for tile in dialog.tiles] == [False, True, True]
    shown = dialog.tiles[0].icon()
    assert shown.pixmap(80, QIcon.Mode.Disabled).toImage() == shown.pixmap(80, QIcon.Mode.Normal).toImage()
    dialog.show()
    dialog.activateWindow()
    qtbot.waitUntil(dialog.isActiveWindow)  # the tiles' keys are the window's shortcuts
    with qtbot.waitSignal(dialog.reading_chosen) as chosen:
        qtbot.keyClick(dialog, Qt.Key.Key_3)
    assert chosen.args == [SketchOrientation(90.0, False)]
    assert dialog.result() == ReadingsDialog.DialogCode.Accepted


def test_compare_the_readings_then_match_in_one_of_them(window, qtbot):
    action, panel = window.actions["compare_readings"], window.matching_panel
    assert action.shortcut().toString() == "Ctrl+Shift+R"
    assert not action.isEnabled() and not panel.compare_readings.isVisible()  # nothing matched yet
    assert window.tools.compare_readings() is None
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    readings = panel.readings
    assert len(readings) > 2 and readings[0][0] == panel.found_orientation
    assert action.isEnabled() and panel.compare_readings.text() == f"Compare the {len(readings)} readings…"
    dialog = window.tools.compare_readings()
    assert [tile.text().split("\n")[0] for tile in dialog.tiles] == [
        f"{rank}. {reading.describe()}" for rank, (reading, _) in enumerate(readings, start=1)
    ]
    third = readings[2][0]
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(dialog.tiles[2], Qt.MouseButton.LeftButton)
    # The matcher was told the third reading and the sketch view turned to it.
    config = window.session.last_match.config
    assert (config.orientation, config.mirrored) == (third.angle, third.mirrored)
    assert window.views["sketch"].orientation == (third.angle, third.mirrored)
    # Told, the matcher ranks no readings; the ones ranked before stay, to try another.
    assert panel.readings == readings and panel.answer_reading == third and action.isEnabled()
    again = window.tools.compare_readings()
    assert [tile.isEnabled() for tile in again.tiles] == [index != 2 for index in range(len(readings))]
    again.reject()
    # A reading none of them is: they are put away.
    panel.set_orientation(SketchOrientation(45.0, False))
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    assert panel.readings == [] and not action.isEnabled() and not panel.compare_readings.isVisible()


def test_another_sketch_puts_the_readings_away(window, qtbot, tmp_path, map_files):
    panel = window.matching_panel
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    assert panel.readings_offered() and panel.found_orientation is not None
    # Another sketch: the cliques stay, by their points, but how the last match read the sketch
    # was another sketch's reading.
    _open_another_sketch(window, tmp_path, map_files)
    assert window.session.correspondences.cliques  # kept, and with them the file's record
    assert panel.readings == [] and panel.found_orientation is None and panel.runner_up is None
    assert not window.actions["compare_readings"].isEnabled() and window.tools.compare_readings() is None
    assert not panel.keep_found.isVisible() and "read the sketch" not in panel.summary.text()
    # Matched, this sketch's readings are offered.
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    assert panel.readings_offered() and "read the sketch" in panel.summary.text()


def test_a_file_of_another_sketch_opened_offers_its_own_readings(window, qtbot, tmp_path, map_files):
    panel = window.matching_panel
    with qtbot.waitSignal(window.session.correspondences_changed, timeout=60_000):
        qtbot.mouseClick(panel.match_button, Qt.MouseButton.LeftButton)
    first = panel.readings
    window.documents.save_as(tmp_path / "first.json")
    _open_another_sketch(window, tmp_path, map_files)
    assert panel.readings == []
    # Opening the first file (another sketch than the one open) offers the readings it recorded.
    window.documents.open_correspondences(tmp_path / "first.json")
    assert [reading for reading, _ in panel.readings] == [reading for reading, _ in first]
    assert panel.found_orientation == first[0][0] and panel.keep_found.text()


def _open_another_sketch(window, tmp_path, map_files) -> None:
    """Open and segment another sketch: the same rooms, one with a pillar drawn in."""
    import cv2

    from ursim_core.segmentation import load_label_image

    image = cv2.imread(str(map_files["sketch"]), cv2.IMREAD_UNCHANGED)
    image[25:28, 20:23] = 0
    cv2.imwrite(str(tmp_path / "other_sketch.png"), image)
    window.session.load_map("sketch", tmp_path / "other_sketch.png")
    window.session.set_segmentation(
        "sketch", load_label_image(map_files["sketch_labels"], shape=window.session.map("sketch").shape)
    )
