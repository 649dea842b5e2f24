"""Node-to-segment springs of 2D meshes: residual and consistent tangent, vectorized.

The 2D counterpart of ``springs.py`` (docs/method.md §5, §6). A spring joins a slave node p to a
master edge with nodes x_0..x_{n-1} (line2 or line3, ``edges.py``); its element node order is
``[master 0..n-1, slave]`` and its element dofs are ``2*k + c``. In the current configuration:

- the slave node is projected orthogonally onto the edge, clamped to ``ξ ∈ [-1, 1]``, giving ξ*,
  q = Σ φ_j x_j, t = q_ξ, r = x_p − q, m = (t_y, −t_x) (t turned clockwise: out of the master
  body), n = m/|m| and the clearance g = r·n;
- the overclosure is d = −(g − gap_shift) and the normal force F_N = ``law.spring_force(d, A)``;
- the internal forces are f_p = −F_N n on the slave node and f_j = −φ_j f_p on master node j.

The tangent is the exact derivative of the forces with respect to the 2(n+1) nodal positions,
the spring area held constant: stationarity r·t = 0 gives H δξ = Σ_k b_k·δx_k with
H = t·t − r·q_ξξ and b_k = w_k t + φ_k,ξ r (w = −φ_j for master nodes, 1 for the slave); at a
projection clamped to an end of the edge (the slave node beside the edge) ξ is fixed (δξ = 0)
unless ``interior_projection`` asks for CalculiX's interior formula everywhere.

Friction (docs/method.md §11, §17): the 3D return map of ``friction.tangential_forces`` on
2-vectors, whose tangent plane is the line of t: the tangential force F_T is added to f_p and its
exact derivative (through ∂ξ/∂x, ∂n/∂x and ∂F_N/∂x) to ∂f_p/∂x; the tangent is then never
symmetrized.
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from dolfinx_ntf.kernels.edges import EdgeType
from dolfinx_ntf.kernels.friction import FrictionInput, tangential_forces
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.springs import SpringEvaluation, _check_finite, _force_per_area

__all__ = ["evaluate_segment_springs", "project_onto_edges"]

# The end constraint ξ = ±1 counts as active when r·t pushes past it by more than this (relative
# to t·t).
_MULTIPLIER_TOL = 1e-10
_MAX_NEWTON = 50


def _planar(coords: np.ndarray, what: str, shape: tuple[int, ...]) -> np.ndarray:
    """The first two coordinates of ``coords`` (…, 2 or 3) as a float array of ``shape``."""
    arr = np.asarray(coords, dtype=float)
    if arr.shape[:-1] != shape or arr.shape[-1] not in (2, 3):
        raise ValueError(f"{what} must have shape {(*shape, '2 or 3')}, got {arr.shape}")
    arr = arr[..., :2]
    _check_finite(what, arr.reshape(shape[0], -1) if shape[0] else arr)
    return arr


def project_onto_edges(
    edge_type: EdgeType,
    master: np.ndarray,
    slave: np.ndarray,
    xi0: np.ndarray | None = None,
) -> np.ndarray:
    """Closest point ξ* ∈ [-1, 1] of each slave node on its edge -> (N, 1).

    Exact for line2; Newton on r·q_ξ = 0 with clamping for line3 (from ``xi0`` or the chord's
    projection).
    """
    chord = master[:, 1] - master[:, 0]
    along = np.einsum("ni,ni->n", slave - master[:, 0], chord) / np.einsum("ni,ni->n", chord, chord)
    xi = np.clip(2.0 * along - 1.0, -1.0, 1.0)
    if edge_type.num_nodes == 2:
        return xi[:, None]
    if xi0 is not None:
        xi = np.clip(np.asarray(xi0, dtype=float).reshape(-1), -1.0, 1.0)
    for _ in range(_MAX_NEWTON):
        phi = edge_type.shape_functions(xi[:, None])
        dphi = edge_type.shape_derivatives(xi[:, None])
        d2phi = edge_type.shape_second_derivatives(xi[:, None])
        r = slave - np.einsum("nj,njc->nc", phi, master)
        t = np.einsum("nj,njc->nc", dphi, master)
        tt = np.einsum("nc,nc->n", t, t)
        h = tt - np.einsum("nc,nc->n", r, np.einsum("nj,njc->nc", d2phi, master))
        h = np.where(h > 1e-3 * tt, h, tt)  # far from convex: a gradient step
        step = np.einsum("nc,nc->n", r, t) / h
        new = np.clip(xi + step, -1.0, 1.0)
        moved = np.abs(new - xi)
        xi = new
        if np.all(moved <= 1e-15):
            break
    return xi[:, None]


def evaluate_segment_springs(
    edge_type: EdgeType,
    master_coords: np.ndarray,
    slave_coords: np.ndarray,
    areas: np.ndarray,
    law: PressureOverclosureLaw,
    *,
    gap_shift: float | np.ndarray = 0.0,
    xi0: np.ndarray | None = None,
    tangent: bool = True,
    symmetric: bool = False,
    area_fallback: bool = True,
    fallback_factor: float = 1.0,
    fallback_ring: bool = False,
    interior_projection: bool = False,
    friction: FrictionInput | None = None,
) -> SpringEvaluation:
    """Forces and tangent of N node-to-segment springs (2D; docs/method.md §5, §6).

    Args:
        edge_type: Type of all master edges.
        master_coords: (N, n, 2 or 3) current coordinates of the master edge nodes (a third
            coordinate, z = 0 of a 2D mesh, is ignored).
        slave_coords: (N, 2 or 3) current coordinates of the slave nodes.
        areas: (N,) spring areas (tributary length times thickness), constant in the tangent.
        law: Pressure-overclosure law.
        gap_shift: Scalar or (N,) shift subtracted from the clearance (docs/method.md §3.5).
        xi0: Optional (N, 1) start points of the projection (line3).
        tangent: Compute the stiffness matrix.
        symmetric: Return (K + Kᵀ)/2 (exact tangent is unsymmetric only at clamped projections).
        area_fallback: Where A = 0, use |q_ξ| (half the length of a straight edge) times
            ``fallback_factor``, and with ``fallback_ring`` times ``2 pi r`` at the projection
            point (ccx's 4|m| of an expanded master face, docs/method.md §26.3).
        fallback_factor: Factor of the fallback area (1: |q_ξ|).
        fallback_ring: The fallback is a ring area: times ``2 pi x_0`` of the projection point.
        interior_projection: Differentiate clamped projections as interior ones (CalculiX).
        friction: Friction state and parameters (vectors of 2 or 3 components, a third one
            ignored): adds the tangential force F_T along the edge to f_p and its derivative to
            the tangent (docs/method.md §17); the tangent is then never symmetrized.

    Returns:
        The evaluation with ``xi`` (N, 1), ``normal`` (N, 2), ``forces`` (N, n+1, 2),
        ``stiffness`` (N, 2(n+1), 2(n+1)) with dofs ``2k + c`` and, with friction,
        ``tangential`` of 2-vectors.
    """
    n = edge_type.num_nodes
    area = np.asarray(areas, dtype=float)
    num = area.shape[0] if area.ndim == 1 else -1
    if num < 0:
        raise ValueError(f"areas must have shape (N,), got {area.shape}")
    master = _planar(master_coords, "master_coords", (num, n))
    slave = _planar(slave_coords, "slave_coords", (num,))
    _check_finite("areas", area)
    if np.any(area < 0.0):
        raise ValueError(f"areas must be >= 0; negative at springs {np.flatnonzero(area < 0)[:10]}")
    shift = np.broadcast_to(np.asarray(gap_shift, dtype=float), (num,))

    xi = project_onto_edges(edge_type, master, slave, xi0)
    phi = edge_type.shape_functions(xi)  # (N, n)
    dphi_master = edge_type.shape_derivatives(xi)
    q = np.einsum("nj,njc->nc", phi, master)
    t = np.einsum("nj,njc->nc", dphi_master, master)
    r = slave - q
    m = np.stack([t[:, 1], -t[:, 0]], axis=1)
    m_norm = np.linalg.norm(m, axis=1)
    degenerate = np.flatnonzero(~(m_norm > 0.0))
    if degenerate.size:
        raise ValueError(f"degenerate master edge (q_xi = 0) at springs {degenerate[:10].tolist()}")
    normal = m / m_norm[:, None]
    gap = np.einsum("nc,nc->n", r, normal)

    if area_fallback:
        fallback = fallback_factor * m_norm
        if fallback_ring:
            fallback = fallback * (2.0 * np.pi * q[:, 0])
        area = np.where(area == 0.0, fallback, area)
    overclosure = -(gap - shift)
    force, dforce = law.spring_force(overclosure, area)
    force = np.asarray(force, dtype=float) * np.ones_like(area)
    dforce = np.asarray(dforce, dtype=float) * np.ones_like(area)
    _check_finite("normal force from the law", force)

    weights = np.concatenate([-phi, np.ones((num, 1))], axis=1)  # (N, n+1)
    dphi = np.concatenate([dphi_master, np.zeros((num, 1))], axis=1)  # (N, n+1)
    derivatives = _Derivatives(None, None, None)
    if tangent:
        derivatives = _derivatives(
            edge_type, master, xi, r, t, normal, m_norm, weights, dphi, interior_projection
        )
    dxi, dnormal, dgap = derivatives

    slave_force = -force[:, None] * normal
    tangential = None
    if friction is not None:
        tangential = tangential_forces(
            weights,
            normal,
            force,
            area,
            _planar_friction(friction, num, n),
            dphi=dphi[:, :, None],
            dxi=None if dxi is None else dxi[:, :, None, :],
            dnormal=dnormal,
            dnormal_force=None if dgap is None else -dforce[:, None, None] * dgap,
        )
        slave_force = slave_force + tangential.force
        symmetric = False
    forces = weights[:, :, None] * slave_force[:, None, :]
    force_per_area = _force_per_area(forces, force, area, overclosure, weights, normal, law)

    stiffness = None
    if tangent:
        # ∂f_p/∂x_kc = dF_N/dd n ⊗ ∂g/∂x_kc − F_N ∂n/∂x_kc (∂d = −∂g), + ∂F_T/∂x_kc.
        dslave = dforce[:, None, None, None] * normal[:, None, :, None] * dgap[:, :, None, :]
        dslave -= force[:, None, None, None] * dnormal  # (N, l, i, c)
        if tangential is not None:
            dslave += tangential.dforce
        # ∂f_k/∂x_l = w_k ∂f_p/∂x_l − φ_k,ξ f_p ⊗ ∂ξ/∂x_l.
        blocks = weights[:, :, None, None, None] * dslave.transpose(0, 2, 1, 3)[:, None]
        blocks -= (
            dphi[:, :, None, None, None]
            * slave_force[:, None, :, None, None]
            * dxi[:, None, None, :, :]
        )
        stiffness = blocks.reshape(num, 2 * (n + 1), 2 * (n + 1))
        _check_finite("stiffness", stiffness)
        if symmetric:
            stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))

    return SpringEvaluation(
        xi=xi,
        phi=phi,
        normal=normal,
        gap=gap,
        overclosure=overclosure,
        normal_force=force,
        area=area,
        forces=forces,
        force_per_area=force_per_area,
        stiffness=stiffness,
        tangential=tangential,
    )


class _Derivatives(typing.NamedTuple):
    """∂ξ/∂x_kc (N, k, c), ∂n_i/∂x_kc (N, k, i, c) and ∂g/∂x_kc (N, k, c), or None."""

    dxi: np.ndarray | None
    dnormal: np.ndarray | None
    dgap: np.ndarray | None


def _derivatives(
    edge_type: EdgeType,
    master: np.ndarray,
    xi: np.ndarray,
    r: np.ndarray,
    t: np.ndarray,
    normal: np.ndarray,
    m_norm: np.ndarray,
    weights: np.ndarray,
    dphi: np.ndarray,
    interior_projection: bool,
) -> _Derivatives:
    """Exact derivatives of the projection ξ*, the normal and the clearance by the nodes."""
    q2 = np.einsum("nj,njc->nc", edge_type.shape_second_derivatives(xi), master)
    h = np.einsum("nc,nc->n", t, t) - np.einsum("nc,nc->n", r, q2)
    b = weights[:, :, None] * t[:, None, :] + dphi[:, :, None] * r[:, None, :]  # (N, k, c)
    free = _free_projection(xi[:, 0], r, t, h) | interior_projection
    singular = free & ~(h > 1e-14 * np.einsum("nc,nc->n", t, t))
    if np.any(singular):
        raise ValueError(
            "singular projection (slave node at a centre of curvature of its master edge) at "
            f"springs {np.flatnonzero(singular)[:10].tolist()}"
        )
    dxi = np.where(free, 1.0 / np.where(free, h, 1.0), 0.0)[:, None, None] * b  # (N, k, c)
    # ∂m/∂x_kc = J (φ_k,ξ e_c + q_ξξ ∂ξ/∂x_kc) with J t = (t_y, −t_x).
    dt = dphi[:, :, None, None] * np.eye(2) + q2[:, None, :, None] * dxi[:, :, None, :]
    dm = np.stack([dt[:, :, 1], -dt[:, :, 0]], axis=2)  # (N, k, i, c)
    projector = np.eye(2) - normal[:, :, None] * normal[:, None, :]
    dnormal = np.einsum("nij,nkjc->nkic", projector / m_norm[:, None, None], dm)
    dgap = weights[:, :, None] * normal[:, None, :] + np.einsum("ni,nkic->nkc", r, dnormal)
    return _Derivatives(dxi, dnormal, dgap)


def _planar_friction(friction: FrictionInput, num: int, n: int) -> FrictionInput:
    """The friction input on 2-vectors (a third component, z = 0 of a 2D mesh, dropped)."""
    displacements = _planar(friction.displacements, "friction displacements", (num, n + 1))
    starts = [
        _planar(value, f"friction {name}", (num,))
        for name, value in (
            ("a_start", friction.a_start),
            ("t_start", friction.t_start),
            ("slip_start", friction.slip_start),
        )
    ]
    return dataclasses.replace(
        friction,
        displacements=displacements,
        a_start=starts[0],
        t_start=starts[1],
        slip_start=starts[2],
    )


def _free_projection(xi: np.ndarray, r: np.ndarray, t: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Whether ξ* moves with the nodes: inside the edge, or at an end with no push past it."""
    push = np.einsum("nc,nc->n", r, t)  # −∂(|r|²/2)/∂ξ: > 0 pushes towards ξ > 1
    tol = _MULTIPLIER_TOL * np.einsum("nc,nc->n", t, t)
    at_end = ((xi >= 1.0) & (push > tol)) | ((xi <= -1.0) & (push < -tol))
    return ~at_end
