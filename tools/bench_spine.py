"""Spine benchmark: per-call fk + jacobian through hexapod_kin vs raw Pinocchio calls.

Both sides use the same Pinocchio model and configurations, measured in the same run; the
ratio (hexapod_kin / raw) is the API's overhead. Target: <= 2x.
"""

from __future__ import annotations

import time

import pinocchio as pin

import hexapod_kin as hk


def _best_per_call(func, qs, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        for q in qs:
            func(q)
        best = min(best, (time.perf_counter() - t0) / len(qs))
    return best


def run(quick: bool = False) -> list[dict]:
    rows = []
    n, repeat = (2_000, 3) if quick else (20_000, 7)
    for source, kw in [("hexabot_leg", {}), ("scara", {}), ("erd:solo12", {"tip": "FL_FOOT"})]:
        model = hk.load(source, **kw)
        m, d, fid = model.model, model.model.createData(), model.tip_id
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        qs = list(model.random_q(n, seed=0))

        def raw(q, m=m, d=d, fid=fid, lwa=lwa):
            pin.forwardKinematics(m, d, q)
            pose = pin.updateFramePlacement(m, d, fid).homogeneous
            jac = pin.computeFrameJacobian(m, d, q, fid, lwa)
            return pose, jac

        def api(q, model=model):
            return model.fk(q), model.jacobian(q)

        def api_fused(q, model=model):
            return model.fk_jacobian(q)

        # Interleave the three so that machine load affects them alike; keep the best of each.
        t_raw = t_api = t_fused = float("inf")
        for _ in range(repeat):
            t_raw = min(t_raw, _best_per_call(raw, qs, 1))
            t_api = min(t_api, _best_per_call(api, qs, 1))
            t_fused = min(t_fused, _best_per_call(api_fused, qs, 1))
        rows.append(
            {
                "chain": source,
                "raw_pin_fk+jac_us": round(t_raw * 1e6, 3),
                "hexapod_kin_fk+jacobian_us": round(t_api * 1e6, 3),
                "ratio": round(t_api / t_raw, 2),
                "hexapod_kin_fk_jacobian_fused_us": round(t_fused * 1e6, 3),
                "ratio_fused": round(t_fused / t_raw, 2),
                "target": "ratio <= 2",
            }
        )
    return rows


if __name__ == "__main__":
    for row in run():
        print(row)
