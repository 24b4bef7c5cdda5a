"""``python -m hexapod_kin``: the same as the ``hexapod-kin`` command."""

from .cli import run

run()
