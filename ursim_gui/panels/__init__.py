"""Side panels of the main window; each one is a thin view over the session (or the campaign).

May import ``ursim_gui.views`` and ``ursim_gui.model``; never the tools, jobs or window.
"""
