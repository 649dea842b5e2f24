"""Small-strain J2 plasticity with isotropic hardening: the radial return map, vectorized.

docs/method.md §21. Tensors are symmetric 3x3 in Mandel notation, 6-vectors
``[xx, yy, zz, sqrt2 xy, sqrt2 xz, sqrt2 yz]``: the dot product of two Mandel vectors is the double
contraction of the tensors and a 6x6 Mandel matrix maps strains to stresses. Given the total strain
``eps``, the committed plastic strain ``eps_p`` and equivalent plastic strain ``alpha`` of every
quadrature point, :func:`return_map` gives the stress, the algorithmic (consistent) tangent
``d sigma / d eps`` and the trial history of the increment (committed by the caller only when the
increment converges). The hardening is CalculiX's ``*PLASTIC`` table
(:class:`IsotropicHardening`): yield stress against equivalent plastic strain, piecewise linear, so
the return map's scalar equation is piecewise linear and solved exactly (no local iterations).

Pure numpy: no dolfinx import.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "IsotropicHardening",
    "ReturnMapping",
    "elastic_matrix",
    "mandel_from_tensor",
    "return_map",
    "tensor_from_mandel",
]

SQRT2 = np.sqrt(2.0)
#: The identity tensor in Mandel notation.
IDENTITY = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
#: Deviatoric projector in Mandel notation (6x6).
DEVIATOR = np.eye(6) - np.outer(IDENTITY, IDENTITY) / 3.0
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def mandel_from_tensor(tensor: npt.ArrayLike) -> np.ndarray:
    """Mandel 6-vectors of symmetric 3x3 tensors, shape (..., 3, 3) -> (..., 6)."""
    t = np.asarray(tensor, dtype=float)
    scale = np.array([1.0, 1.0, 1.0, SQRT2, SQRT2, SQRT2])
    return np.stack([t[..., i, j] for i, j in _PAIRS], axis=-1) * scale


def tensor_from_mandel(vector: npt.ArrayLike) -> np.ndarray:
    """Symmetric 3x3 tensors of Mandel 6-vectors, shape (..., 6) -> (..., 3, 3)."""
    v = np.asarray(vector, dtype=float)
    out = np.empty((*v.shape[:-1], 3, 3))
    for k, (i, j) in enumerate(_PAIRS):
        value = v[..., k] if k < 3 else v[..., k] / SQRT2
        out[..., i, j] = value
        out[..., j, i] = value
    return out


def elastic_matrix(youngs_modulus: float, poisson_ratio: float) -> np.ndarray:
    """Isotropic Hooke's law as a 6x6 Mandel matrix, ``3K P_vol + 2 mu P_dev``."""
    if not (youngs_modulus > 0 and -1 < poisson_ratio < 0.5):
        raise ValueError(
            f"isotropic elasticity needs E > 0 and -1 < nu < 0.5, got E = {youngs_modulus}, "
            f"nu = {poisson_ratio}"
        )
    mu = youngs_modulus / (2 * (1 + poisson_ratio))
    bulk = youngs_modulus / (3 * (1 - 2 * poisson_ratio))
    return bulk * np.outer(IDENTITY, IDENTITY) + 2 * mu * DEVIATOR


@dataclass(frozen=True)
class IsotropicHardening:
    """CalculiX's ``*PLASTIC`` table (isotropic hardening): yield stress against plastic strain.

    The Mises yield stress is piecewise linear in the equivalent plastic strain between the
    table's points. Beyond the last point it stays constant (``beyond="constant"``, perfectly
    plastic) or follows the last segment's slope (``beyond="linear"``, what
    :meth:`linear` uses).

    Attributes:
        yield_stress: Yield stresses (> 0), one per table line.
        plastic_strain: Equivalent plastic strains, increasing from 0.
        beyond: ``"constant"`` or ``"linear"`` beyond the last point.
    """

    yield_stress: tuple[float, ...]
    plastic_strain: tuple[float, ...]
    beyond: str = "constant"

    def __post_init__(self) -> None:
        """Check the table (``ValueError`` naming the line that is wrong)."""
        stress = np.asarray(self.yield_stress, dtype=float)
        strain = np.asarray(self.plastic_strain, dtype=float)
        owner = "IsotropicHardening"
        if stress.ndim != 1 or stress.shape != strain.shape or stress.size < 1:
            raise ValueError(
                f"{owner}: yield_stress and plastic_strain must be 1-D of the same length >= 1, "
                f"got shapes {stress.shape} and {strain.shape}"
            )
        if not (np.all(np.isfinite(stress)) and np.all(np.isfinite(strain))):
            raise ValueError(f"{owner}: the table must be finite")
        if strain[0] != 0.0:
            raise ValueError(
                f"{owner}: the first line's plastic strain must be 0 (initial yield), got "
                f"{strain[0]}"
            )
        bad = np.flatnonzero(np.diff(strain) <= 0)
        if bad.size:
            raise ValueError(
                f"{owner}: plastic strains must increase, line {bad[0] + 2} has "
                f"{strain[bad[0] + 1]} after {strain[bad[0]]}"
            )
        if np.any(stress <= 0):
            line = int(np.flatnonzero(stress <= 0)[0])
            raise ValueError(
                f"{owner}: yield stresses must be > 0, line {line + 1} has {stress[line]}"
            )
        if self.beyond not in ("constant", "linear"):
            raise ValueError(f"{owner}: beyond must be 'constant' or 'linear', got {self.beyond!r}")
        if self.beyond == "linear" and stress.size < 2:
            raise ValueError(f"{owner}: beyond='linear' needs at least two lines")

    @classmethod
    def linear(cls, initial_yield_stress: float, hardening_modulus: float) -> IsotropicHardening:
        """Linear hardening ``sigma_y = sigma_y0 + H alpha`` for every ``alpha >= 0``.

        Args:
            initial_yield_stress: sigma_y0 > 0.
            hardening_modulus: H (0: perfectly plastic).
        """
        return cls(
            (float(initial_yield_stress), float(initial_yield_stress) + float(hardening_modulus)),
            (0.0, 1.0),
            beyond="linear",
        )

    def segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start strain, start stress and slope of each linear piece (the last one unbounded)."""
        stress = np.asarray(self.yield_stress, dtype=float)
        strain = np.asarray(self.plastic_strain, dtype=float)
        slopes = np.diff(stress) / np.diff(strain)
        last = slopes[-1] if self.beyond == "linear" else 0.0
        return strain, stress, np.append(slopes, last)

    def __call__(self, alpha: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Yield stress and hardening slope at the equivalent plastic strains ``alpha``.

        At a table point the slope is the right segment's.
        """
        strain, stress, slopes = self.segments()
        alpha = np.asarray(alpha, dtype=float)
        piece = np.clip(np.searchsorted(strain, alpha, side="right") - 1, 0, None)
        return stress[piece] + slopes[piece] * (alpha - strain[piece]), slopes[piece]


@dataclass(frozen=True)
class ReturnMapping:
    """Result of :func:`return_map` at n points (trial history of the increment).

    Attributes:
        stress: Stresses, Mandel (n, 6).
        tangent: Algorithmic tangent ``d stress / d strain``, Mandel (n, 6, 6).
        plastic_strain: Plastic strains at the end of the increment, Mandel (n, 6).
        equivalent_plastic_strain: alpha at the end of the increment, (n,).
        plastic: Points that yielded in this increment, (n,) bool.
    """

    stress: np.ndarray
    tangent: np.ndarray
    plastic_strain: np.ndarray
    equivalent_plastic_strain: np.ndarray
    plastic: np.ndarray


def return_map(
    strain: npt.ArrayLike,
    plastic_strain: npt.ArrayLike,
    equivalent_plastic_strain: npt.ArrayLike,
    youngs_modulus: float,
    poisson_ratio: float,
    hardening: IsotropicHardening,
) -> ReturnMapping:
    """The radial return of J2 plasticity at every point, with its consistent tangent.

    Trial stress ``C (eps - eps_p_n)``; where its Mises stress ``q_tr`` exceeds the yield stress
    ``sigma_y(alpha_n)``, the increment ``dg`` of equivalent plastic strain solves
    ``q_tr - 3 mu dg = sigma_y(alpha_n + dg)`` (exactly: one linear piece of the table holds the
    root), and the deviatoric stress is scaled back along ``n = s_tr / |s_tr|``. The tangent is
    ``K I x I + 2 mu theta P_dev - 2 mu theta_bar n x n`` with ``theta = 1 - 3 mu dg / q_tr`` and
    ``theta_bar = 1/(1 + H/(3 mu)) - 3 mu dg / q_tr`` (H the slope of the piece).

    Args:
        strain: Total strains, Mandel (n, 6).
        plastic_strain: Committed plastic strains, Mandel (n, 6).
        equivalent_plastic_strain: Committed alpha, (n,).
        youngs_modulus: E > 0.
        poisson_ratio: -1 < nu < 0.5.
        hardening: The yield stress table; every slope must exceed ``-3 mu`` (softening faster
            than that has no unique return).
    """
    eps = np.asarray(strain, dtype=float).reshape(-1, 6)
    eps_p = np.asarray(plastic_strain, dtype=float).reshape(-1, 6)
    alpha = np.asarray(equivalent_plastic_strain, dtype=float).reshape(-1)
    if not (eps.shape == eps_p.shape and alpha.shape == eps.shape[:1]):
        raise ValueError(
            f"return_map: strain {eps.shape}, plastic_strain {eps_p.shape} and "
            f"equivalent_plastic_strain {alpha.shape} must have the same number of points"
        )
    C = elastic_matrix(youngs_modulus, poisson_ratio)
    mu = youngs_modulus / (2 * (1 + poisson_ratio))
    starts, values, slopes = hardening.segments()
    if np.any(slopes <= -3 * mu):
        raise ValueError(f"return_map: hardening slopes must exceed -3 mu = {-3 * mu:.6g}")
    trial = (eps - eps_p) @ C
    deviator = trial @ DEVIATOR
    norm = np.linalg.norm(deviator, axis=1)
    q_trial = np.sqrt(1.5) * norm
    yield_now, _ = hardening(alpha)
    plastic = q_trial - yield_now > 1e-12 * yield_now
    # one candidate root per linear piece j: q_tr - 3 mu dg = s_j + h_j (alpha + dg - e_j)
    a = alpha[plastic, None]
    candidates = (q_trial[plastic, None] - values - slopes * (a - starts)) / (3 * mu + slopes)
    ends = np.append(starts[1:], np.inf)
    reached = a + candidates
    inside = (reached >= starts - 1e-14 * (1 + starts)) & (reached <= ends * (1 + 1e-14))
    inside &= candidates >= 0
    if not np.all(inside.any(axis=1)):  # cannot happen for slopes > -3 mu, but never silently
        raise ValueError("return_map: no piece of the hardening table holds the return's root")
    piece = inside.shape[1] - 1 - np.argmax(inside[:, ::-1], axis=1)  # the right piece at a knot
    rows = np.arange(piece.size)
    dg = np.zeros_like(alpha)
    H = np.zeros_like(alpha)
    dg[plastic] = candidates[rows, piece]
    H[plastic] = slopes[piece]
    direction = np.zeros_like(deviator)
    np.divide(deviator, norm[:, None], out=direction, where=norm[:, None] > 0)
    stress = trial - (2 * mu * np.sqrt(1.5) * dg)[:, None] * direction
    ratio = np.zeros_like(alpha)
    np.divide(3 * mu * dg, q_trial, out=ratio, where=plastic)
    theta = 1 - ratio
    theta_bar = np.where(plastic, 1 / (1 + H / (3 * mu)) - ratio, 0.0)
    bulk = youngs_modulus / (3 * (1 - 2 * poisson_ratio))
    tangent = (
        bulk * np.outer(IDENTITY, IDENTITY)[None]
        + (2 * mu * theta)[:, None, None] * DEVIATOR[None]
        - (2 * mu * theta_bar)[:, None, None] * direction[:, :, None] * direction[:, None, :]
    )
    return ReturnMapping(
        stress=stress,
        tangent=tangent,
        plastic_strain=eps_p + (np.sqrt(1.5) * dg)[:, None] * direction,
        equivalent_plastic_strain=alpha + dg,
        plastic=plastic,
    )
