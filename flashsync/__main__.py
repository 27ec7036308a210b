"""``python -m flashsync`` runs the command line."""

import sys

from flashsync.cli import process_main

if __name__ == "__main__":  # not when a worker process of a local Dask cluster imports it
    sys.exit(process_main())
