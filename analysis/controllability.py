"""Controllability of the four-thruster layout (the paper's Sec. "Controllability").

The paper follows Deng et al.: the thruster configuration matrix ``B`` has one column per
thruster, the unit thrust vector ``f_i`` over the moment it makes about the centre of gravity,
``r_i x f_i``; its rank is the number of independently controllable degrees of freedom. The
paper states rank 4 (surge, heave, roll, yaw) for NemeSys and gives no geometry.

Here ``B`` is built from the twin's geometry (:class:`sim.model.VehicleParams`), body
frame x forward, y starboard, z down, origin at the centre of gravity:

* thruster 1 (port) and 2 (starboard), horizontal, pushing forward, at y = -/+ ``arm_h_m``;
* thruster 3 (port) and 4 (starboard), vertical, pushing down, at y = -/+ ``arm_v_m``;

all at the centre of gravity's station and height (the twin gives them no x or z offset).
:func:`allocation_matrix` computes it, :func:`analyse` its rank and null directions with
numpy (SVD), and :func:`model_matrix` measures the same matrix from the twin's equations of
motion (one thruster at 1 N, the initial accelerations times the inertias), so the table is
the model's, not a second copy of it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from analysis.stability import config_params
from sim.model import Vehicle, VehicleParams

#: Wrench rows: forces (N) then moments (N m) about the centre of gravity, body axes.
WRENCH = ("X surge", "Y sway", "Z heave", "K roll", "M pitch", "N yaw")
THRUSTERS = ("T1 port, horizontal", "T2 stbd, horizontal", "T3 port, vertical", "T4 stbd, vertical")
#: Why the design leaves each unactuated direction to something else.
WHY_NOT_ACTUATED = {
    "Y sway": (
        "non-holonomic like a torpedo: a sideways move is flown as yaw then surge (the "
        "planner's paths and the line-of-sight guidance never ask for sway); sway is passive "
        "and heavily damped (Yv, Yvv and 10 kg added mass in the twin)"
    ),
    "M pitch": (
        "passively stable: the same centre-of-gravity-below-buoyancy offset h that rights roll "
        "gives a restoring pitch moment W h sin(theta) (the paper's restoring-moment equation "
        "holds for any horizontal axis), and no pattern needs a pitched attitude; the twin "
        "holds pitch at zero"
    ),
}


def thruster_geometry(
    params: VehicleParams | None = None,
) -> list[tuple[tuple[float, float, float], tuple[float, float, float]]]:
    """(position m, unit thrust direction) of thrusters 1..4, body frame, origin at the CG."""
    q = params or VehicleParams()
    return [
        ((0.0, -q.arm_h_m, 0.0), (1.0, 0.0, 0.0)),
        ((0.0, q.arm_h_m, 0.0), (1.0, 0.0, 0.0)),
        ((0.0, -q.arm_v_m, 0.0), (0.0, 0.0, 1.0)),
        ((0.0, q.arm_v_m, 0.0), (0.0, 0.0, 1.0)),
    ]


def allocation_matrix(params: VehicleParams | None = None) -> NDArray[np.float64]:
    """The paper's ``B = [f_i ; r_i x f_i]``: 6 x 4, wrench per newton of each thruster."""
    cols = []
    for r, f in thruster_geometry(params):
        rv, fv = np.array(r), np.array(f)
        cols.append(np.concatenate([fv, np.cross(rv, fv)]))
    return np.array(cols, dtype=np.float64).T


def model_matrix(params: VehicleParams | None = None, dt_s: float = 1e-6) -> NDArray[np.float64]:
    """The same matrix measured on the twin: from rest, upright, neutrally buoyant, one
    thruster held at 1 N for one tiny step; each wrench component is the inertia times the
    acceleration it causes. The twin has no pitch degree of freedom, so its M row is 0."""
    q = params or VehicleParams()
    neutral = config_params(0.0, replace(q, buoyancy_margin_n=0.0))
    inertia = (
        q.mass_kg + q.a11_kg,
        q.mass_kg + q.a22_kg,
        q.mass_kg + q.a33_kg,
        q.ix_kgm2 + q.a44_kgm2,
        q.iz_kgm2 + q.a66_kgm2,
    )
    cols = []
    for i in range(4):
        veh = Vehicle(neutral, z_m=5.0)
        thrust = tuple(1.0 if j == i else 0.0 for j in range(4))
        veh.t1, veh.t2, veh.t3, veh.t4 = thrust
        veh.command(*thrust)
        veh.step(dt_s)
        rates = (veh.u, veh.v, veh.w, veh.p, veh.r)
        x, y, z, k, n = (m * v / dt_s for m, v in zip(inertia, rates, strict=True))
        cols.append([x, y, z, k, 0.0, n])
    return np.array(cols, dtype=np.float64).T


@dataclass(frozen=True, slots=True)
class Controllability:
    matrix: NDArray[np.float64]  # 6 x 4
    rank: int
    actuated: tuple[str, ...]  # wrench directions in B's column space
    unactuated: tuple[str, ...]  # B's left null space, by wrench row
    redundant: int  # dimension of B's null space: thrust mixes that make no wrench
    max_wrench: dict[str, tuple[float, float]]  # per actuated direction: (most -, most +)


def _named(vectors: NDArray[np.float64]) -> tuple[str, ...]:
    """Each basis vector named by its wrench row when it is one axis (else a mix)."""
    names = []
    for v in vectors:
        k = int(np.argmax(np.abs(v)))
        pure = np.allclose(np.delete(v, k), 0.0, atol=1e-9)
        names.append(WRENCH[k] if pure else "mix " + ", ".join(f"{c:+.2f}" for c in v))
    return tuple(names)


def _order(name: str) -> int:
    return WRENCH.index(name) if name in WRENCH else len(WRENCH)


def analyse(params: VehicleParams | None = None) -> Controllability:
    """Rank (numpy ``matrix_rank``), the wrench directions the thrusters cannot make (the
    left null space from the SVD) and the largest wrench each actuated axis can reach."""
    q = params or VehicleParams()
    b = allocation_matrix(q)
    rank = int(np.linalg.matrix_rank(b))
    u, _, _ = np.linalg.svd(b)
    null_left = u[:, rank:].T
    unactuated = tuple(sorted(_named(np.round(null_left, 12)), key=_order))
    actuated = tuple(n for n in WRENCH if n not in unactuated)
    hi, lo = q.thrust_max_n, q.thrust_min_n
    # each thruster in [lo, hi]: the extremes of a linear map lie at the box's corners
    corners = np.array([[a, b_, c, d] for a in (lo, hi) for b_ in (lo, hi) for c in (lo, hi)
                        for d in (lo, hi)])  # fmt: skip
    wrenches = corners @ b.T
    max_wrench = {
        name: (float(wrenches[:, k].min()), float(wrenches[:, k].max()))
        for k, name in enumerate(WRENCH)
        if name in actuated
    }
    return Controllability(b, rank, actuated, unactuated, b.shape[1] - rank, max_wrench)


__all__ = [
    "THRUSTERS",
    "WHY_NOT_ACTUATED",
    "WRENCH",
    "Controllability",
    "allocation_matrix",
    "analyse",
    "model_matrix",
    "thruster_geometry",
]
