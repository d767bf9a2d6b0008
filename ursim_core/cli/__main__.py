import sys

from ursim_core.cli.main import main

sys.exit(main())
