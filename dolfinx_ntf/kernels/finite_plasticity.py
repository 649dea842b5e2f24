"""Finite-strain J2 plasticity (Simo's multiplicative model), vectorized: ccx's NLGEOM ``*PLASTIC``.

docs/method.md §21.7. From the deformation gradient ``F`` and the committed inverse plastic right
Cauchy-Green tensor ``Cp_inv`` and equivalent plastic strain ``alpha`` of every point: the trial
isochoric elastic left Cauchy-Green tensor ``be = J^(-2/3) F Cp_inv F^T``, the Kirchhoff deviator
``s = mu dev(be)``, the pressure part ``J p = K (J^2 - 1) / 2``; where the Mises value of the
Cauchy deviator ``sqrt(3/2) |s| / J`` exceeds the yield stress, the radial return
``s = s_tr - 2 mu_bar dg n`` (``mu_bar = mu tr(be) / 3``) with ``alpha += sqrt(2/3) dg`` solving
``sqrt(3/2) |s_tr| / J - 3 (mu_bar / J) d_alpha = sigma_y(alpha + d_alpha)`` exactly on the
table's linear pieces, and the updated ``be = s / mu + tr(be_tr) / 3 I``. The first
Piola-Kirchhoff stress is ``tau F^-T``. Its derivative ``dP/dF`` (the consistent tangent) is taken
by complex steps: every operation above is analytic within a piece of the table, so the
imaginary part of ``P(F + i h E_kl) / h`` is the derivative to round-off (h = 1e-30).

Pure numpy: no dolfinx import.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .plasticity import IsotropicHardening

__all__ = ["FiniteReturnMapping", "finite_return_map"]

_STEP = 1e-30


@dataclass(frozen=True)
class FiniteReturnMapping:
    """Result of :func:`finite_return_map` at n points (trial history of the increment).

    Attributes:
        first_piola: First Piola-Kirchhoff stresses, (n, 3, 3).
        tangent: ``dP_ij / dF_kl``, (n, 3, 3, 3, 3).
        cauchy: Cauchy stresses, (n, 3, 3).
        inverse_plastic_metric: ``Cp^-1`` at the end of the increment, (n, 3, 3).
        equivalent_plastic_strain: alpha at the end of the increment, (n,).
        plastic: Points that yielded in this increment, (n,) bool.
    """

    first_piola: np.ndarray
    tangent: np.ndarray
    cauchy: np.ndarray
    inverse_plastic_metric: np.ndarray
    equivalent_plastic_strain: np.ndarray
    plastic: np.ndarray


def _det(F: np.ndarray) -> np.ndarray:
    """Determinants of (n, 3, 3) arrays by cofactors (analytic, so complex steps pass through)."""
    return (
        F[:, 0, 0] * (F[:, 1, 1] * F[:, 2, 2] - F[:, 1, 2] * F[:, 2, 1])
        - F[:, 0, 1] * (F[:, 1, 0] * F[:, 2, 2] - F[:, 1, 2] * F[:, 2, 0])
        + F[:, 0, 2] * (F[:, 1, 0] * F[:, 2, 1] - F[:, 1, 1] * F[:, 2, 0])
    )


def _inverse(F: np.ndarray, J: np.ndarray) -> np.ndarray:
    """Inverses of (n, 3, 3) arrays by the adjugate."""
    cof = np.empty_like(F)
    for i in range(3):
        for j in range(3):
            r = [k for k in range(3) if k != i]
            c = [k for k in range(3) if k != j]
            minor = F[:, r[0], c[0]] * F[:, r[1], c[1]] - F[:, r[0], c[1]] * F[:, r[1], c[0]]
            cof[:, i, j] = (-1) ** (i + j) * minor
    return np.swapaxes(cof, 1, 2) / J[:, None, None]


def _state(
    F: np.ndarray,
    cp_inv: np.ndarray,
    alpha: np.ndarray,
    mu: float,
    bulk: float,
    hardening: IsotropicHardening,
    piece: np.ndarray | None,
) -> tuple[np.ndarray, ...]:
    """Stresses and history at ``F`` (real or complex).

    ``piece`` is the table piece of each point (-1 elastic), None to choose it from the values
    (real ``F`` only).
    """
    J = _det(F)
    be = J[:, None, None] ** (-2.0 / 3.0) * np.einsum("nij,njk,nlk->nil", F, cp_inv, F)
    trace = np.einsum("nii->n", be)
    eye = np.eye(3)
    s = mu * (be - (trace / 3.0)[:, None, None] * eye)
    norm = np.sqrt(np.einsum("nij,nij->n", s, s))
    q_trial = np.sqrt(1.5) * norm / J  # Mises value of the Cauchy deviator
    mu_bar = mu * trace / 3.0 / J
    starts, values, slopes = hardening.segments()
    if piece is None:
        yield_now, _ = hardening(alpha.real)
        plastic = q_trial.real - yield_now > 1e-12 * yield_now
        piece = np.full(alpha.shape, -1, dtype=np.int64)
        if np.any(plastic):
            a = alpha.real[plastic, None]
            m = mu_bar.real[plastic, None]
            candidates = (q_trial.real[plastic, None] - values - slopes * (a - starts)) / (
                3 * m + slopes
            )
            ends = np.append(starts[1:], np.inf)
            reached = a + candidates
            inside = (reached >= starts - 1e-14 * (1 + starts)) & (reached <= ends * (1 + 1e-14))
            inside &= candidates >= 0
            if not np.all(inside.any(axis=1)):
                raise ValueError(
                    "finite_return_map: no piece of the hardening table holds the return's root"
                )
            piece[plastic] = inside.shape[1] - 1 - np.argmax(inside[:, ::-1], axis=1)
    plastic = piece >= 0
    j = np.maximum(piece, 0)
    d_alpha = (q_trial - values[j] - slopes[j] * (alpha - starts[j])) / (3 * mu_bar + slopes[j])
    d_alpha = np.where(plastic, d_alpha, 0.0)
    safe = np.where(norm.real > 0, norm, 1.0)
    n = s / safe[:, None, None]
    dg = np.sqrt(1.5) * d_alpha  # the Kirchhoff deviator's return: 2 mu_bar J dg, per J
    s = s - (2 * mu_bar * J * dg)[:, None, None] * n
    tau = s + (0.5 * bulk * (J * J - 1.0))[:, None, None] * eye
    F_inv = _inverse(F, J)
    first_piola = np.einsum("nij,nkj->nik", tau, F_inv)
    be_new = s / mu + (trace / 3.0)[:, None, None] * eye
    cp_new = J[:, None, None] ** (2.0 / 3.0) * np.einsum("nij,njk,nlk->nil", F_inv, be_new, F_inv)
    return first_piola, tau / J[:, None, None], cp_new, alpha + d_alpha, piece


def finite_return_map(
    deformation_gradient: npt.ArrayLike,
    inverse_plastic_metric: npt.ArrayLike,
    equivalent_plastic_strain: npt.ArrayLike,
    youngs_modulus: float,
    poisson_ratio: float,
    hardening: IsotropicHardening,
) -> FiniteReturnMapping:
    """Simo's finite-strain radial return at every point, with ``dP/dF`` by complex steps.

    Args:
        deformation_gradient: ``F``, (n, 3, 3), ``det F > 0``.
        inverse_plastic_metric: Committed ``Cp^-1`` (identity at the start), (n, 3, 3).
        equivalent_plastic_strain: Committed alpha, (n,).
        youngs_modulus: E > 0 (``mu = E / (2 (1 + nu))``, ``K = E / (3 (1 - 2 nu))``).
        poisson_ratio: -1 < nu < 0.5.
        hardening: The yield stress (true stress) against the equivalent plastic strain.
    """
    F = np.asarray(deformation_gradient, dtype=float).reshape(-1, 3, 3)
    cp_inv = np.asarray(inverse_plastic_metric, dtype=float).reshape(-1, 3, 3)
    alpha = np.asarray(equivalent_plastic_strain, dtype=float).reshape(-1)
    if not (F.shape == cp_inv.shape and alpha.shape == F.shape[:1]):
        raise ValueError(
            f"finite_return_map: deformation_gradient {F.shape}, inverse_plastic_metric "
            f"{cp_inv.shape} and equivalent_plastic_strain {alpha.shape} must have the same "
            "number of points"
        )
    if not (youngs_modulus > 0 and -1 < poisson_ratio < 0.5):
        raise ValueError(
            f"finite_return_map: E > 0 and -1 < nu < 0.5 needed, got {youngs_modulus}, "
            f"{poisson_ratio}"
        )
    J = _det(F)
    if np.any(~(J > 0)):
        bad = int(np.flatnonzero(~(J > 0))[0])
        raise ValueError(f"finite_return_map: det F = {J[bad]:.6g} <= 0 at point {bad}")
    mu = youngs_modulus / (2 * (1 + poisson_ratio))
    bulk = youngs_modulus / (3 * (1 - 2 * poisson_ratio))
    slopes = hardening.segments()[2]
    if np.any(slopes <= -3 * mu):
        raise ValueError(f"finite_return_map: hardening slopes must exceed -3 mu = {-3 * mu:.6g}")
    P, sigma, cp_new, alpha_new, piece = _state(F, cp_inv, alpha, mu, bulk, hardening, None)
    tangent = np.empty((F.shape[0], 3, 3, 3, 3))
    for k in range(3):
        for m in range(3):
            Fc = F.astype(complex)
            Fc[:, k, m] += 1j * _STEP
            Pc = _state(Fc, cp_inv.astype(complex), alpha.astype(complex), mu, bulk, hardening,
                        piece)[0]  # fmt: skip
            tangent[:, :, :, k, m] = Pc.imag / _STEP
    return FiniteReturnMapping(
        first_piola=P,
        tangent=tangent,
        cauchy=sigma,
        inverse_plastic_metric=cp_new,
        equivalent_plastic_strain=alpha_new,
        plastic=piece >= 0,
    )
