"""``python -m symmech``: the command line (see :mod:`symmech.cli`)."""

import sys

from symmech.cli import main

sys.exit(main())
