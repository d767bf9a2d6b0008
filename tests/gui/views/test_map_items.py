"""Graphics items of a map view (ursim_gui.views.map_items): the label overlay image."""

from __future__ import annotations

from ursim_gui.model.region_style import region_colour_table


def test_lut_image_equals_the_numpy_overlay(labels3):
    """The view's one-gather ARGB image shows exactly overlay_rgba's colours."""
    from ursim_gui.model.region_style import overlay_rgba
    from ursim_gui.views.map_items import lut_qimage

    table = region_colour_table(3, alpha=255)
    image, _pixels = lut_qimage(labels3, table)
    expected = overlay_rgba(labels3, table)
    for row, col in ((0, 0), (10, 10), (30, 75), (40, 120)):
        colour = image.pixelColor(col, row)
        assert (colour.red(), colour.green(), colour.blue(), colour.alpha()) == tuple(expected[row, col])
