"""What :func:`hexapod_kin.symbolic.derive` derives: a source turned into a chain and its base.

A :class:`~hexapod_kin.params.Chain` as it is; a preset by name; a hexapod leg with its mount
as the chain's base pose (so ``p`` and ``J`` are in the body frame, like the loaded model);
any URDF (path, text, ``erd:NAME``, a loaded model of one) read back with
:func:`~hexapod_kin.chain_from_urdf`.
"""

from __future__ import annotations

from typing import Any

from ..exceptions import ParameterError, choices
from ..params import Chain, Hexapod

__all__ = ["chain_of"]


def _leg(robot: Hexapod, tip: str) -> Any:
    """The leg mount whose foot frame is ``tip`` (``None``: no such leg)."""
    return next((leg for leg in robot.legs if tip == f"{leg.name}_{leg.chain.tip}"), None)


def _mounted(robot: Hexapod, tip: str, base: str) -> tuple[Chain, str] | None:
    leg = _leg(robot, tip)
    if leg is not None and base == f"{leg.name}_{leg.chain.base}":
        return leg.chain, base
    if leg is not None and base == robot.body:
        pose = leg.transform() @ leg.chain.base_matrix
        moved = leg.chain.replace(base=robot.body, base_pose=pose, name=f"{robot.name}_{leg.name}")
        return moved, base
    return None


def chain_of(
    source: Any, base: str | None = None, tip: str | None = None
) -> tuple[Chain, str, str]:
    """``(chain, reference (base frame name), tip name)`` for a source (see :func:`derive`)."""
    if isinstance(source, Chain):
        if base is None and tip is None:
            return source, source.base, source.tip
        return _from_urdf(source, base, tip)
    if isinstance(source, Hexapod):
        if tip is not None:
            found = _mounted(source, tip, base or source.body)
            if found is not None:
                return found[0], found[1], tip
            return _from_urdf(source, base, tip)
        raise ParameterError(
            f"derive: source is the robot {source.name!r} (a Hexapod); pick one leg with "
            f"tip= (feet {choices(source.foot_frames)}) or derive robot.legs[0].chain"
        )
    if isinstance(source, str):
        from .. import robots

        if source in robots.names():
            return chain_of(robots.get(source), base, tip)
        if source.lower().endswith((".toml", ".yaml", ".yml")):  # a table file: its own table
            from ..sources import resolve_source

            params = resolve_source(source).params
            if isinstance(params, (Chain, Hexapod)):
                return chain_of(params, base, tip)
        return _from_urdf(source, base, tip)
    params = getattr(source, "params", None)
    m_base, m_tip = getattr(source, "base", None), getattr(source, "tip", None)
    if isinstance(m_base, str) and isinstance(m_tip, str) and base is None and tip is None:
        nq = getattr(source, "nq", None)
        leg = _leg(params, m_tip) if isinstance(params, Hexapod) else None
        if isinstance(params, Hexapod) and (leg is None or nq != leg.chain.nq):
            raise ParameterError(
                f"derive: the model {getattr(source, 'name', '?')!r} moves {nq} joints (the whole "
                f"robot); pick one leg with tip= (feet {choices(params.foot_frames)})"
            )
        if isinstance(params, Chain) and params.base == m_base and params.tip == m_tip:
            if nq == params.nq:
                return params, m_base, m_tip
        if isinstance(params, Hexapod):
            found = _mounted(params, m_tip, m_base)
            if found is not None:
                return found[0], found[1], m_tip
        return _from_urdf(source, None, None)
    if hasattr(source, "model") and hasattr(source, "fk"):
        return _from_urdf(source, base, tip)
    raise ParameterError(
        f"derive: source={source!r} has no Khalil table; give a Chain, a preset name, a URDF "
        "(path, text or erd:NAME) or a loaded model"
    )


def _from_urdf(source: Any, base: str | None, tip: str | None) -> tuple[Chain, str, str]:
    from .._fromurdf import chain_from_urdf
    from ..exceptions import HexapodKinError

    try:
        chain = chain_from_urdf(source, base=base, tip=tip)
    except HexapodKinError:
        raise
    except Exception as exc:  # noqa: BLE001 - say what the source was
        raise ParameterError(f"derive: source={source!r} could not be read: {exc}") from None
    return chain, chain.base, chain.tip
