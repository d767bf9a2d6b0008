"""Qt views of the model: the map view and its layers, overlays, connectors, status bar, figure export.

May import ``ursim_gui.model`` and Qt; never the panels, tools, jobs or window above it.
They draw what the model holds and forward input to it; they keep no annotation state.

- :mod:`~ursim_gui.views.map_view`: :class:`MapView`, one zoomable map with its region layers.
- :mod:`~ursim_gui.views.map_items`, :mod:`~ursim_gui.views.region_layers`: its graphics items.
- :mod:`~ursim_gui.views.connectors`: lines between matched regions across the two views.
- :mod:`~ursim_gui.views.session_binding`: session signals -> drawing, clicks -> session calls.
- :mod:`~ursim_gui.views.status_bar`, :mod:`~ursim_gui.views.figure_export`,
  :mod:`~ursim_gui.views.messages` (error boxes), :mod:`~ursim_gui.views.file_dialogs`
  (dialogs that cannot freeze on /proc), :mod:`~ursim_gui.views.theme` (dark palette).
"""
