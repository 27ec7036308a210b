"""``python -m flashsync`` runs the command line."""

import sys

from flashsync.cli import main

sys.exit(main())
