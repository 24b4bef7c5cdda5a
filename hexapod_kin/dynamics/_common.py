"""Shared checks of the dynamics package: models, numbers, vectors, inertials."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pinocchio as pin

from .._fields import read_only
from ..exceptions import ParameterError
from ..kinematics import as_model
from ..model import check_inertials as loader_check_inertials

__all__ = ["as_model", "check_inertials", "check_state", "finite_vector", "read_only",
           "zero_gravity_model"]  # fmt: skip

#: Relative tolerance on the principal moments of inertia (a moment <= tol * largest is zero).
INERTIA_RTOL = 1e-12


def finite_vector(name: str, value: Any, n: int, *, nonnegative: bool = False) -> np.ndarray:
    """``value`` as a float array of shape (n,); a scalar is broadcast.

    Raises:
        ParameterError: Wrong shape, non-numbers, non-finite or (``nonnegative``) negative.

    """
    try:
        if np.asarray(value).dtype.kind in "USbO":
            raise TypeError
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ParameterError(
            f"{name}={value!r} is not a number or a sequence of {n} numbers",
            parameter=name,
            value=value,
            allowed=f"{n} finite numbers",
        ) from None
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.shape != (n,):
        msg = f"{name} has shape {arr.shape}; expected ({n},) or a scalar"
        raise ParameterError(msg, parameter=name, value=value, allowed=f"{n} finite numbers")
    if not np.all(np.isfinite(arr)) or (nonnegative and np.any(arr < 0)):
        need = "finite values >= 0" if nonnegative else "finite values"
        msg = f"{name}={arr.tolist()} is not allowed; {need} are needed"
        raise ParameterError(msg, parameter=name, value=arr.tolist(), allowed=need)
    return arr


def _body_name(model: pin.Model, joint: int) -> str:
    """The link moved by ``joint`` (its first body frame), else the joint's name."""
    for frame in model.frames:
        if frame.parentJoint == joint and frame.type == pin.FrameType.BODY:
            return str(frame.name)
    return str(model.names[joint])


def _inertial_problem(inertia: pin.Inertia) -> str | None:
    """Why a body inertia is implausible for dynamics, or None when it is fine."""
    mass = float(inertia.mass)
    lever = np.asarray(inertia.lever, dtype=float)
    tensor = np.asarray(inertia.inertia, dtype=float)
    if not (math.isfinite(mass) and np.all(np.isfinite(lever)) and np.all(np.isfinite(tensor))):
        return "non-finite mass, centre of mass or inertia"
    if mass <= 0:
        return f"mass {mass!r} kg (a moving body needs mass > 0)"
    moments = np.linalg.eigvalsh(0.5 * (tensor + tensor.T))
    if moments[0] <= INERTIA_RTOL * max(moments[-1], 0.0) or moments[0] <= 0:
        return (
            f"inertia about the centre of mass not positive definite (principal moments "
            f"{[float(m) for m in moments]} kg m^2)"
        )
    return None


def check_inertials(model: Any) -> None:
    """Refuse a model whose moving bodies have implausible inertials (before any dynamics).

    The loader's verdict first (``hexapod_kin.model.check_inertials``); then every body moved
    by a joint (``model.inertias[i]``, i >= 1) needs a finite mass > 0 and a positive-definite
    inertia about its centre of mass, else ABA can divide by zero (cached per model).

    Args:
        model: A loaded model.

    Raises:
        UrdfError: The loader found an implausible inertial (names the link).
        ParameterError: Naming the link (and its joint) and what is wrong with its inertial.

    """
    if hasattr(model, "inertia_defects"):
        loader_check_inertials(model)  # the loader's own verdict, link by link

    def scan() -> tuple[str, str, str] | None:
        m = model.model
        for j in range(1, m.njoints):
            problem = _inertial_problem(m.inertias[j])
            if problem is not None:
                return _body_name(m, j), str(m.names[j]), problem
        return None

    found = model.cached("dynamics.inertials", scan) if hasattr(model, "cached") else scan()
    if found is not None:
        link, joint, problem = found
        raise ParameterError(
            f"link {link!r} (moved by joint {joint!r}) of {model.name!r} has a physically "
            f"implausible inertial for dynamics: {problem}; fix its <inertial> in the URDF",
            parameter="inertial",
            value=link,
            allowed="mass > 0, positive-definite inertia",
        )


def check_state(model: Any, value: Any, name: str) -> np.ndarray:
    """A (nq,) joint vector checked by the model (``ConfigurationError`` otherwise)."""
    return np.array(model.check_q(value, name), dtype=float)


def zero_gravity_model(model: Any) -> pin.Model:
    """A copy of the Pinocchio model with gravity switched off (cached per model)."""

    def build() -> pin.Model:
        copy = pin.Model(model.model)
        copy.gravity = pin.Motion.Zero()
        return copy

    return model.cached("dynamics.zero_gravity", build) if hasattr(model, "cached") else build()
