"""``python -m bladelab`` runs the command line."""

import sys

from bladelab.cli import main

sys.exit(main())
