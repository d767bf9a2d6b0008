"""``python -m ursim_gui``: same as the ``ursim-gui`` command."""

from ursim_gui.app import main

# Guarded: job worker processes are spawned and import this module as __mp_main__.
if __name__ == "__main__":
    raise SystemExit(main())
