"""Contact damping of node-to-face springs (CalculiX ``*CONTACT DAMPING``): force and tangent.

Pure numpy, vectorized over N springs (docs/method.md §29). For each spring, with element nodes
``k = 0..n`` (master face nodes, then the slave node), weights ``w_k`` (``-phi_j`` for master node
``j``, ``+1`` for the slave) and nodal velocities ``v_k``:

- relative velocity at the projection point ``v_rel = sum_k w_k v_k = v_p - sum_j phi_j v_j``;
- projector ``P = f I + (1 - f) n n^T`` (``f`` the tangent fraction, ``n`` the master normal);
- damping force on the slave node (internal, like ``-F_N n``) ``F_D = c A P v_rel``; the master
  nodes get ``-phi_j F_D`` through the spring's weights.

The velocities come from the time integrator as an affine function of the displacement,
``v_k = v0_k + rate u_k`` (``rate = gamma/(beta dt)`` for Newmark), so the tangent
``dF_D/dx_l`` holds ``c A P w_l rate`` (the damping matrix) plus the derivatives of the projection
weights, of the normal and, where the spring area is CalculiX's fallback ``factor |m|``, of the
area.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DampingForce", "DampingInput", "damping_forces"]


@dataclass
class DampingInput:
    """What the damping force of N springs needs besides the projection kinematics.

    Attributes:
        velocities: ``(N, n+1, 3)`` velocities ``v_k`` of the element nodes (master face nodes,
            then the slave node).
        rate: ``dv/du`` of the time integrator (``gamma/(beta dt)``; 0: velocities held fixed).
        coefficient: Damping constant ``c`` [force time/length^3] (scalar or ``(N,)``).
        tangent_fraction: ``f``: the tangential damping constant is ``f c``.
    """

    velocities: np.ndarray
    rate: float
    coefficient: float | np.ndarray
    tangent_fraction: float = 0.0


@dataclass
class DampingForce:
    """Damping results of N springs.

    Attributes:
        force: ``(N, 3)`` damping force ``F_D`` added to the slave node's internal force.
        dforce: ``(N, n+1, 3, 3)`` ``dF_D_i/dx_kc``, or None without tangent.
        relative_velocity: ``(N, 3)`` ``v_rel``.
    """

    force: np.ndarray
    dforce: np.ndarray | None
    relative_velocity: np.ndarray


def damping_forces(
    weights: np.ndarray,
    normal: np.ndarray,
    area: np.ndarray,
    damping: DampingInput,
    *,
    dphi: np.ndarray | None = None,
    dxi: np.ndarray | None = None,
    dnormal: np.ndarray | None = None,
    darea: np.ndarray | None = None,
) -> DampingForce:
    """Damping force of N springs and, with the derivatives given, its tangent.

    Args:
        weights: ``(N, n+1)`` spring weights ``w_k``.
        normal: ``(N, 3)`` unit master normal at the projection point.
        area: ``(N,)`` spring areas.
        damping: Velocities and constants.
        dphi: ``(N, n+1, 2)`` ``dw_k/dxi`` up to the sign (``phi_j,alpha``; 0 for the slave).
        dxi: ``(N, n+1, 2, 3)`` ``dxi_alpha/dx_kc``.
        dnormal: ``(N, n+1, 3, 3)`` ``dn_i/dx_kc``.
        darea: ``(N, n+1, 3)`` ``dA/dx_kc`` (None: the areas are held constant).

    Returns:
        The force; ``dforce`` is None unless ``dphi``, ``dxi`` and ``dnormal`` are given.
    """
    num, nodes = weights.shape
    velocities = np.asarray(damping.velocities, dtype=float)
    if velocities.shape != (num, nodes, 3):
        raise ValueError(
            f"contact damping: velocities must have shape ({num}, {nodes}, 3), "
            f"got {velocities.shape}"
        )
    if not np.all(np.isfinite(velocities)):
        bad = np.flatnonzero(~np.isfinite(velocities).all(axis=(1, 2)))
        raise ValueError(f"contact damping: velocities not finite at springs {bad[:10].tolist()}")
    c = np.broadcast_to(np.asarray(damping.coefficient, dtype=float), (num,))
    fraction = float(damping.tangent_fraction)
    if not (np.all(np.isfinite(c)) and np.all(c >= 0.0) and np.isfinite(fraction)):
        raise ValueError(
            "contact damping: the coefficient and the tangent fraction must be finite, the "
            f"coefficient >= 0; got {c[:5].tolist()}, {fraction!r}"
        )
    relative = np.einsum("nk,nki->ni", weights, velocities)
    normal_part = np.einsum("ni,ni->n", normal, relative)
    projected = fraction * relative + (1.0 - fraction) * normal_part[:, None] * normal
    scale = c * area
    force = scale[:, None] * projected
    if dphi is None or dxi is None or dnormal is None:
        return DampingForce(force, None, relative)

    # d(v_rel)/dx_l = w_l rate I - sum_alpha (sum_k phi_k,alpha v_k) (x) dxi_alpha/dx_l
    eye = np.eye(3)
    dvel = float(damping.rate) * weights[:, :, None, None] * eye
    dvel -= np.einsum("nka,nki,nlac->nlic", dphi, velocities, dxi)
    # d(P v)/dx_l = P d(v_rel) + (1 - f) [n (dn^T v_rel) + (n.v_rel) dn]
    dprojected = (
        fraction * dvel
        + (1.0 - fraction)
        * normal[:, None, :, None]
        * np.einsum("nj,nljc->nlc", normal, dvel)[:, :, None, :]
    )
    dprojected += (1.0 - fraction) * (
        normal[:, None, :, None] * np.einsum("nj,nljc->nlc", relative, dnormal)[:, :, None, :]
        + normal_part[:, None, None, None] * dnormal
    )
    dforce = scale[:, None, None, None] * dprojected
    if darea is not None:
        dforce += (c[:, None] * projected)[:, None, :, None] * darea[:, :, None, :]
    return DampingForce(force, dforce, relative)
