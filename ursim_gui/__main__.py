"""``python -m ursim_gui``: same as the ``ursim-gui`` command."""

from ursim_gui.app import main

raise SystemExit(main())
