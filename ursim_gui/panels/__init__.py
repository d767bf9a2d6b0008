"""Side panels of the main window; each one is a thin view over the session."""
