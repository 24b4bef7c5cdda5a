"""``python -m hexapod_kin``: the same as the ``hexapod-kin`` command."""

from ._entry import run

run()
