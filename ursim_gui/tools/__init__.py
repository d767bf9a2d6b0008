"""Interactive tools that edit an image: the sketch drawing canvas, segmentation editing.

May import ``ursim_gui.views`` and ``ursim_gui.model``; never the panels, jobs or window.

- :mod:`~ursim_gui.tools.sketch_canvas`: draw a new sketch.
- :mod:`~ursim_gui.tools.segmentation_editor`: merge, split by a line, paint / erase walls.
"""
