"""Interactive tools that edit an image: the sketch drawing canvas.

May import ``ursim_gui.views`` and ``ursim_gui.model``; never the panels, jobs or window.
"""
