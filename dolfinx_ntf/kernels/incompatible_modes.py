"""Incompatible-mode hexahedra (CalculiX's C3D8I): stiffness with the internal modes condensed.

Pure numpy, vectorized over cells (docs/method.md §22). The eight-node trilinear hexahedron's
displacement is enriched by three bubble modes ``1 - xi_i^2`` per displacement component (nine
internal parameters ``alpha`` per cell, zero at the nodes, discontinuous between cells) after
Taylor, Beresford and Wilson (1976), the version CalculiX's manual names. The modes' gradients are
taken with the Jacobian ``J0`` at the cell centre. Taylor et al. scale them by ``det J0 / det J``
so that their strains integrate to zero over any cell: a linear displacement field then gives
``alpha = 0`` and the exact constant stress on any mesh (the patch test; ``taylor=True``).
CalculiX 2.20 leaves the scaling out (``taylor=False``; measured against its displacements on
distorted meshes, docs/method.md §22): the same element on parallelepipeds (``det J`` constant),
failing the patch test on other shapes. Small strain, isotropic elasticity, 2x2x2 Gauss points.

The element equations ``[[Kuu, Kua], [Kau, Kaa]] [u, alpha] = [f, 0]`` are condensed per cell:
``K = Kuu - Kua Kaa^-1 Kau`` and ``alpha = -Kaa^-1 Kau u``. ``Kuu`` is the plain trilinear
hexahedron's (C3D8's) stiffness, so :func:`condensation` returns the *correction*
``-Kua Kaa^-1 Kau`` that turns an assembled C3D8 stiffness into the C3D8I one.

Conventions: nodes in tensor order (node ``k`` at ``xi = (2 (k & 1) - 1, 2 (k >> 1 & 1) - 1,
2 (k >> 2 & 1) - 1)``, dolfinx's hexahedron), element dofs node-major (``3 k + i``), Gauss points
with ``xi`` fastest (CalculiX's order of its integration points).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "GAUSS_POINTS",
    "Condensation",
    "condensation",
    "condensed_stiffness",
    "gauss_point_strains",
    "stiffness",
]

_CORNERS = np.array([[(k & 1), (k >> 1) & 1, (k >> 2) & 1] for k in range(8)]) * 2.0 - 1.0
_G = 1.0 / np.sqrt(3.0)
#: (8, 3) 2x2x2 Gauss points in ``[-1, 1]^3``, ``xi`` fastest (weights 1).
GAUSS_POINTS = np.array([[x, y, z] for z in (-_G, _G) for y in (-_G, _G) for x in (-_G, _G)])


def _shape_derivatives(points: np.ndarray) -> np.ndarray:
    """(Q, 8, 3) derivatives of the trilinear shape functions at ``points`` (Q, 3)."""
    factors = 1.0 + points[:, None, :] * _CORNERS[None, :, :]  # (Q, 8, 3): 1 + xi_i xi_i^k
    derivative = np.empty_like(factors)
    for i in range(3):
        others = [j for j in range(3) if j != i]
        derivative[..., i] = (
            _CORNERS[None, :, i] * factors[..., others[0]] * factors[..., others[1]] / 8.0
        )
    return derivative


def _bubble_derivatives(points: np.ndarray) -> np.ndarray:
    """(Q, 3, 3) derivatives ``d(1 - xi_m^2)/d xi_i`` of the three bubble modes ``m``."""
    return -2.0 * points[:, :, None] * np.eye(3)[None, :, :]


_DN = _shape_derivatives(GAUSS_POINTS)  # (8 points, 8 nodes, 3)
_DN0 = _shape_derivatives(np.zeros((1, 3)))[0]  # at the centre
_DP = _bubble_derivatives(GAUSS_POINTS)  # (8 points, 3 modes, 3)


def _check(coordinates: np.ndarray) -> np.ndarray:
    """``coordinates`` as a finite (C, 8, 3) float array."""
    x = np.asarray(coordinates, dtype=float)
    if x.ndim != 3 or x.shape[1:] != (8, 3) or not np.all(np.isfinite(x)):
        raise ValueError(
            f"incompatible modes: cell coordinates must be finite (C, 8, 3), got shape {x.shape}"
        )
    return x


def _gradients(x: np.ndarray, taylor: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Shape-function and bubble gradients ``(C, Q, 8, 3)``, ``(C, Q, 3, 3)``; ``w det J``."""
    jacobian = np.einsum("qki,ckj->cqji", _DN, x)  # J[j, i] = dx_j / dxi_i
    det = np.linalg.det(jacobian)
    bad = np.argwhere(det <= 0.0)
    if bad.size:
        c, q = bad[0]
        raise ValueError(
            f"incompatible modes: cell {int(c)} has det J = {det[c, q]:.3g} <= 0 at Gauss point "
            f"{int(q) + 1} (inverted or degenerate hexahedron; {len(bad)} such points)"
        )
    inverse = np.linalg.inv(jacobian)  # dxi_i / dx_j
    grad_n = np.einsum("qki,cqij->cqkj", _DN, inverse)
    jacobian0 = np.einsum("ki,ckj->cji", _DN0, x)
    det0 = np.linalg.det(jacobian0)
    grad_p = np.einsum("qmi,cij->cqmj", _DP, np.linalg.inv(jacobian0))
    if taylor:  # zero mean strain of the modes on any cell
        grad_p = grad_p * (det0[:, None] / det)[:, :, None, None]
    return grad_n, grad_p, det  # Gauss weights are 1


def stiffness(
    grad_a: np.ndarray, grad_b: np.ndarray, weight: np.ndarray, mu: np.ndarray, lmbda: np.ndarray
) -> np.ndarray:
    """(C, 3 A, 3 B) isotropic elastic stiffness coupling fields with gradients ``a`` and ``b``.

    Args:
        grad_a: (C, Q, A, 3) gradients of the first fields (one per column block of 3).
        grad_b: (C, Q, B, 3) gradients of the second fields.
        weight: (C, Q) quadrature weights times ``det J``.
        mu: (C,) shear modulus.
        lmbda: (C,) Lamé's first parameter.
    """
    lam = (np.asarray(lmbda, float)[:, None] * weight)[:, :, None, None]
    shear = (np.asarray(mu, float)[:, None] * weight)[:, :, None, None]
    # K[a i, b j] = sum_q lambda g_ai g_bj + mu g_aj g_bi + mu delta_ij g_a . g_b
    cells, _, na, _ = grad_a.shape
    nb = grad_b.shape[2]
    block = np.einsum("cqai,cqbj->caibj", grad_a * lam, grad_b)
    block += np.einsum("cqaj,cqbi->caibj", grad_a * shear, grad_b)
    dot = np.einsum("cqak,cqbk->cab", grad_a * shear, grad_b)
    block += dot[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
    return block.reshape(cells, 3 * na, 3 * nb)


@dataclass(frozen=True)
class Condensation:
    """The condensed internal modes of C cells.

    Attributes:
        correction: (C, 24, 24) ``-Kua Kaa^-1 Kau``, added to the trilinear stiffness.
        recovery: (C, 9, 24) ``-Kaa^-1 Kau``: the internal parameters ``alpha = recovery u``
            (mode-major: ``3 m + i`` is component ``i`` of mode ``m``).
        bubble_gradients: (C, 8, 3, 3) gradients of the three modes at the Gauss points.
        shape_gradients: (C, 8, 8, 3) gradients of the trilinear shape functions there.
    """

    correction: np.ndarray
    recovery: np.ndarray
    bubble_gradients: np.ndarray
    shape_gradients: np.ndarray


def condensation(
    coordinates: np.ndarray, mu: np.ndarray, lmbda: np.ndarray, *, taylor: bool = True
) -> Condensation:
    """Condense the nine internal modes of each cell (linear elasticity).

    Args:
        coordinates: (C, 8, 3) node coordinates in tensor order.
        mu: (C,) shear modulus per cell (or one value).
        lmbda: (C,) Lamé's first parameter per cell (or one value).
        taylor: Scale the modes' gradients by ``det J0 / det J`` (passes the patch test on any
            hexahedron); False is CalculiX 2.20's C3D8I.

    Raises:
        ValueError: bad shapes, non-finite values or an inverted cell (its index).
    """
    x = _check(coordinates)
    cells = x.shape[0]
    mu = np.broadcast_to(np.asarray(mu, float), (cells,))
    lmbda = np.broadcast_to(np.asarray(lmbda, float), (cells,))
    grad_n, grad_p, weight = _gradients(x, taylor)
    k_ua = stiffness(grad_n, grad_p, weight, mu, lmbda)
    k_aa = stiffness(grad_p, grad_p, weight, mu, lmbda)
    recovery = -np.linalg.solve(k_aa, np.swapaxes(k_ua, 1, 2))
    correction = k_ua @ recovery
    correction = 0.5 * (correction + np.swapaxes(correction, 1, 2))  # symmetric to round-off
    return Condensation(correction, recovery, grad_p, grad_n)


def condensed_stiffness(
    coordinates: np.ndarray, mu: np.ndarray, lmbda: np.ndarray, *, taylor: bool = True
) -> np.ndarray:
    """(C, 24, 24) the C3D8I element stiffness: trilinear part plus :func:`condensation`'s.

    Args:
        coordinates: (C, 8, 3) node coordinates in tensor order.
        mu: (C,) shear modulus per cell (or one value).
        lmbda: (C,) Lamé's first parameter per cell (or one value).
        taylor: As in :func:`condensation`.
    """
    x = _check(coordinates)
    cells = x.shape[0]
    mu = np.broadcast_to(np.asarray(mu, float), (cells,))
    lmbda = np.broadcast_to(np.asarray(lmbda, float), (cells,))
    condensed = condensation(x, mu, lmbda, taylor=taylor)
    grad_n, _, weight = _gradients(x, taylor)
    return stiffness(grad_n, grad_n, weight, mu, lmbda) + condensed.correction


def gauss_point_strains(condensed: Condensation, displacements: np.ndarray) -> np.ndarray:
    """(C, 8, 3, 3) small strains at the Gauss points, the internal modes included.

    Args:
        condensed: The cells' :func:`condensation`.
        displacements: (C, 24) nodal displacements (node-major).
    """
    u = np.asarray(displacements, float).reshape(-1, 8, 3)
    alpha = np.einsum("cmd,cd->cm", condensed.recovery, u.reshape(-1, 24)).reshape(-1, 3, 3)
    grad = np.einsum("cqkj,cki->cqij", condensed.shape_gradients, u)
    grad += np.einsum("cqmj,cmi->cqij", condensed.bubble_gradients, alpha)
    return 0.5 * (grad + np.swapaxes(grad, 2, 3))
