"""Masses and inertias: each link's ``<inertial>``, and each moving body Pinocchio builds.

Principal moments by :func:`numpy.linalg.eigvalsh`: loading a model never imports numba.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from lxml import etree

from ..exceptions import UrdfError
from .limits import GYRATION_FACTOR, GYRATION_MAX, INERTIA_FLOOR, TRIANGLE_RTOL
from .parse import error_at, number_of, origin_of, single


def principal_moments(
    ixx: float, iyy: float, izz: float, ixy: float, ixz: float, iyz: float
) -> tuple[float, float, float]:
    """The principal moments [kg m^2], ascending, of the inertia with these entries [kg m^2]."""
    e = np.linalg.eigvalsh(_matrix((ixx, iyy, izz, ixy, ixz, iyz)))
    return (float(e[0]), float(e[1]), float(e[2]))


def _matrix(values: Sequence[float]) -> np.ndarray:
    """The symmetric 3×3 inertia of ``(ixx, iyy, izz, ixy, ixz, iyz)``."""
    ixx, iyy, izz, ixy, ixz, iyz = values
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=float)


def _record(err: UrdfError, name: str, defects: list[tuple[str, str]] | None) -> None:
    """Raise ``err``, or (lenient mode: ``defects`` given) record it as ``(name, message)``."""
    if defects is None:
        raise err
    defects.append((name, str(err)))


@dataclass
class _Inertial:
    """A link's checked ``<inertial>`` (raw numbers; matrices only built when needed)."""

    mass: float
    values: tuple[float, float, float, float, float, float]  # ixx iyy izz ixy ixz iyz
    eig: tuple[float, float, float]  # principal moments [kg m^2], sorted
    element: etree._Element | None  # the <inertial>

    @property
    def present(self) -> bool:
        return self.mass > 0.0 or any(self.values)

    @property
    def definite(self) -> bool:
        return _definite(self.eig)

    @property
    def triangle(self) -> bool:
        return _triangle(self.eig)

    def in_link(self) -> tuple[np.ndarray, np.ndarray]:
        """Centre of mass [m] and inertia about it [kg m^2], in link axes."""
        rot, com = origin_of(self.element)
        return com, rot @ _matrix(self.values) @ rot.T


_NO_INERTIAL = _Inertial(0.0, (0.0,) * 6, (0.0, 0.0, 0.0), None)


def _definite(eig: Sequence[float]) -> bool:
    return eig[0] > 1e-12 * eig[2] + INERTIA_FLOOR


def _triangle(eig: Sequence[float]) -> bool:
    return eig[0] + eig[1] >= eig[2] * (1.0 - TRIANGLE_RTOL)


def _eig_text(eig: Sequence[float]) -> str:
    return "[" + ", ".join(f"{e:.6g}" for e in eig) + "]"


def link_inertial(link: etree._Element, defects: list[tuple[str, str]] | None = None) -> _Inertial:
    """Check a link's ``<inertial>``: mass >= 0, six finite entries, not indefinite.

    With ``defects`` (lenient mode) a defect is recorded there instead of raised.
    """
    inertial = single(link, "inertial", required=False)
    if inertial is None:
        return _NO_INERTIAL
    single(inertial, "origin", required=False)
    mass_el = single(inertial, "mass", required=True)
    inertia_el = single(inertial, "inertia", required=True)
    assert mass_el is not None and inertia_el is not None
    mass = number_of(mass_el, "value")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    ixx, ixy, ixz, iyy, iyz, izz = (number_of(inertia_el, k) for k in keys)
    eig = principal_moments(ixx, iyy, izz, ixy, ixz, iyz)
    scale = max(abs(ixx), abs(iyy), abs(izz), abs(ixy), abs(ixz), abs(iyz))
    if eig[0] < -(1e-9 * scale + INERTIA_FLOOR):
        values = " ".join(f"{k}={inertia_el.get(k)}" for k in keys)
        why = f"inertia is indefinite (principal moments {_eig_text(eig)})"
        err = error_at(
            inertia_el, f"{values}: {why}; an inertia tensor must be positive semi-definite"
        )
        _record(err, str(link.get("name")), defects)
    return _Inertial(mass, (ixx, iyy, izz, ixy, ixz, iyz), eig, inertial)


def robot_size(offsets: Sequence[np.ndarray]) -> float:
    """The robot's size [m]: the sum of its joints' offsets (no two points of it are farther)."""
    return math.fsum(float(np.linalg.norm(o)) for o in offsets)


def check_gyration(
    name: str,
    link: etree._Element,
    inertial: _Inertial,
    size: float,
    defects: list[tuple[str, str]] | None = None,
) -> None:
    """Refuse (or record in ``defects``) a radius of gyration beyond :data:`GYRATION_FACTOR`.

    ``sqrt(I_max / m)``: where the link's whole mass would give its largest moment.
    """
    if inertial.mass <= 0.0 or inertial.element is None:
        return
    radius = math.sqrt(max(inertial.eig[2], 0.0) / inertial.mass)
    limit = max(GYRATION_MAX, GYRATION_FACTOR * size)
    if radius <= limit:
        return
    err = error_at(
        inertial.element.find("inertia"),
        f"link {name!r} has a radius of gyration sqrt(I_max / m) = {radius:.4g} m (largest "
        f"principal moment {inertial.eig[2]:.6g} kg m^2, mass {inertial.mass:g} kg), more than "
        f"{GYRATION_FACTOR:g} times the robot's size ({size:.4g} m, the sum of its joint "
        f"offsets) and {GYRATION_MAX:g} m: no link of this robot can have it (units?)",
    )
    _record(err, name, defects)


def check_moving_body(
    jname: str,
    child: str,
    link_el: dict[str, etree._Element],
    inertials: dict[str, _Inertial],
    fixed_children: dict[str, list[tuple[str, etree._Element]]],
    defects: list[tuple[str, str]] | None = None,
) -> None:
    """The body of joint ``jname`` (``child`` and its fixed subtree): mass > 0, a physical inertia.

    Positive definite, obeying the triangle inequality; with ``defects`` (lenient mode) a
    failure is recorded there as ``(child, message)`` instead of raised.
    """
    # Members with their pose in the child frame (poses computed only if >1 carries mass).
    members: list[tuple[str, etree._Element | None]] = [(child, None)]
    stack = [child]
    while stack:
        for grandchild, joint in fixed_children[stack.pop()]:
            members.append((grandchild, joint))
            stack.append(grandchild)
    parts = [n for n, _ in members if inertials[n].present]
    total = math.fsum(inertials[n].mass for n in parts)
    if total <= 0.0:
        why = f"the link moved by joint {jname!r} has no mass (nor do links fixed to it)"
        err = error_at(link_el[child], f"{why}; a moving link needs <inertial> with mass > 0",
                       "name", child)  # fmt: skip
        return _record(err, child, defects)
    if len(parts) == 1:
        eig = inertials[parts[0]].eig  # rotation-invariant
    elif any(inertials[n].definite for n in parts) and all(inertials[n].triangle for n in parts):
        # Sums of physical inertias (tr(S)·E − S with S >= 0, moved by the parallel-axis
        # theorem, also of that form) stay physical, and adding a definite one makes the
        # sum definite: nothing to compute.
        return
    else:
        pose: dict[str, tuple[np.ndarray, np.ndarray]] = {child: (np.eye(3), np.zeros(3))}
        for name, joint in members[1:]:
            assert joint is not None
            rot_p, pos_p = pose[joint.find("parent").get("link")]
            r_j, p_j = origin_of(joint)
            pose[name] = (rot_p @ r_j, rot_p @ p_j + pos_p)
        coms, mats, masses = [], [], []
        for name in parts:
            rot, pos = pose[name]
            com_l, mat_l = inertials[name].in_link()
            coms.append(rot @ com_l + pos)
            mats.append(rot @ mat_l @ rot.T)
            masses.append(inertials[name].mass)
        com = sum(m * c for m, c in zip(masses, coms)) / total
        mat = np.zeros((3, 3))
        for m, c, inertia in zip(masses, coms, mats):
            dc = c - com
            mat += inertia + m * (float(dc @ dc) * np.eye(3) - np.outer(dc, dc))
        eig = principal_moments(mat[0, 0], mat[1, 1], mat[2, 2], mat[0, 1], mat[0, 2], mat[1, 2])
    own = inertials[child].element
    where = own.find("inertia") if own is not None and len(parts) == 1 else link_el[child]
    merged = (
        "" if len(parts) == 1 else f" (merged with the links fixed to it: {len(parts)} inertials)"
    )
    if not _definite(eig):
        why = (
            f"has an inertia that is not positive definite (principal moments {_eig_text(eig)} "
            f"kg m^2, mass {total:g} kg); a moving link needs a positive-definite inertia"
        )
    elif not _triangle(eig):
        why = (
            f"has principal moments {_eig_text(eig)} kg m^2 that violate the triangle "
            "inequality I1 + I2 >= I3 (no real body has them)"
        )
    else:
        return
    _record(error_at(where, f"the body moved by joint {jname!r}{merged} {why}"), child, defects)
