"""Forward kinematics of a Khalil table in plain numpy (the independent reference).

Re-exported by :mod:`hexapod_kin.params`; a chain's base and tool poses are included.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from .params import Chain

__all__ = ["table_fk", "table_position_jacobian", "table_transforms"]


def _as_q(chain: Chain, q: Any) -> np.ndarray:
    """``q`` as a finite (nq,) float array for ``chain`` (the table layer: no model needed)."""
    from .exceptions import ConfigurationError

    names = list(chain.joint_names or ())
    allowed = f"{chain.nq} finite numbers (joints {names})"
    try:
        arr = np.asarray(q, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ConfigurationError(
            f"q={q!r} is not a sequence of numbers", parameter="q", value=q, allowed=allowed
        ) from None
    if arr.shape != (chain.nq,):
        problem = f"q has {arr.size} values; chain {chain.name!r} has {chain.nq} joints {names}"
    elif not np.all(np.isfinite(arr)):
        problem = f"q={arr.tolist()} contains non-finite values"
    else:
        return arr
    raise ConfigurationError(problem, parameter="q", value=arr.tolist(), allowed=allowed)


def table_transforms(chain: Chain, q: Any) -> list[np.ndarray]:
    """Every ``^{j-1}T_j`` of the table at ``q`` ((n,) in [rad] / [m]), 4×4 each, in order."""
    values = iter(_as_q(chain, q).tolist())
    return [row.transform(next(values)) if row.is_joint else row.transform() for row in chain.rows]


def table_fk(chain: Chain, q: Any) -> np.ndarray:
    """``T_base_tip = base · ^0T_1 ··· ^{n-1}T_n · tool`` (4×4) at ``q`` (n,) in [rad] / [m].

    The product of the Khalil transforms in plain numpy: the independent reference every
    Pinocchio result is checked against.

    Raises:
        ConfigurationError: If ``q`` has the wrong length or non-finite values.

    """
    t = chain.base_matrix
    for tj in table_transforms(chain, q):
        t = t @ tj
    return t @ chain.tool_matrix


_GZ = np.array([[0.0, -1, 0, 0], [1, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]])
_GT = np.array([[0.0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 0]])


def table_position_jacobian(chain: Chain, q: Any) -> np.ndarray:
    """The tip's 3×n position Jacobian (base frame, base and tool included), exactly.

    ``∂(T_1···T_n)/∂q_j = (T_1···T_j)·G_j·(T_{j+1}···T_n)``, ``G_j`` the generator of ``Rz``
    (revolute) or ``Tz`` (prismatic): the *indirect* method, no finite differences.
    """
    ts = table_transforms(chain, q)
    ts[0] = chain.base_matrix @ ts[0]
    ts.append(chain.tool_matrix)  # after the last row: the generators act before it
    prefix = [np.eye(4)]
    for t in ts:
        prefix.append(prefix[-1] @ t)
    suffix = [np.eye(4)] * (len(ts) + 1)
    for j in range(len(ts) - 1, -1, -1):
        suffix[j] = ts[j] @ suffix[j + 1]
    gens = {j: _GZ if chain.rows[j].sigma == "revolute" else _GT for j in chain.joint_rows}
    return np.column_stack([(prefix[j + 1] @ g @ suffix[j + 1])[:3, 3] for j, g in gens.items()])
