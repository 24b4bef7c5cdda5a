"""``python -m hexapod_kin``: the same as the ``hexapod-kin`` command."""

import sys

from .cli import main

sys.exit(main())
