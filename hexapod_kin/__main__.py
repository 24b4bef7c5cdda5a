"""``python -m hexapod_kin``: the same as the ``hexapod-kin`` command."""

import sys

try:
    from .cli import run
except KeyboardInterrupt:  # Ctrl-C while the package loads: one line, status 130
    print("hexapod-kin: interrupted", file=sys.stderr)
    sys.exit(130)

run()
