"""The main window: its composition, actions and shortcuts, file commands, dialogs.

May import everything below it (panels, tools, jobs, views, model); only ``ursim_gui.app``
and ``ursim_gui.bench`` import it.
"""
