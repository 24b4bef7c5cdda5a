"""Load URDF files in a child process and report each outcome as one JSON line.

Used by ``tests/test_gate.py`` so that a crash of Pinocchio (a segfault) shows up as a failed
test naming the case, not as a lost test run. Usage::

    python tests/_urdf_runner.py FILE [FILE ...]

For every file it prints ``{"case": FILE, "started": true}`` before loading and then
``{"case": FILE, "error": CLASS | null, "message": str, "fk_finite": bool | null,
"warnings": [str, ...]}``; a crash
leaves a "started" line without its result.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _load_one(path: Path) -> dict[str, object]:
    import warnings

    import numpy as np

    from hexapod_kin.kinematics import load

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            model = load(path)
        except Exception as exc:  # report every class, the parent asserts which one
            return {
                "error": type(exc).__name__,
                "message": str(exc),
                "fk_finite": None,
                "warnings": [str(w.message) for w in caught],
            }
    finite = True
    for q in (model.neutral(), *model.random_q(5, seed=0)):
        finite &= bool(np.all(np.isfinite(model.fk(q))))
    return {
        "error": None,
        "message": "",
        "fk_finite": finite,
        "nq": model.nq,
        "warnings": [str(w.message) for w in caught],
    }


def main(argv: list[str]) -> int:
    """Load every file of ``argv`` and print the JSON lines."""
    for name in argv:
        print(json.dumps({"case": name, "started": True}), flush=True)
        result = {"case": name, **_load_one(Path(name))}
        print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
