"""``python -m navfdi`` runs the command line."""

import sys

from navfdi.cli import main

sys.exit(main())
