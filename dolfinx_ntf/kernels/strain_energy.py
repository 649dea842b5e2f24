"""Strain energy density of a material point, accumulated over increments: vectorized.

docs/method.md §36. CalculiX 2.20's ``ENER`` of a plastic point is not a potential: it integrates
the stress power over the increments with the trapezoidal rule,
``W_n+1 = W_n + (S_n + S_n+1) : (E_n+1 - E_n) / 2``, where ``(S, E)`` is the Cauchy stress and the
small strain without NLGEOM, the second Piola-Kirchhoff stress and the Green-Lagrange strain with
it (per unit reference volume; measured). For a linear elastic point the rule gives
``S : E / 2`` exactly, whatever the increments. Pure numpy: no dolfinx import.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = ["green_lagrange_pair", "trapezoidal_energy"]


def trapezoidal_energy(
    energy: npt.ArrayLike,
    stress_old: npt.ArrayLike,
    stress_new: npt.ArrayLike,
    strain_old: npt.ArrayLike,
    strain_new: npt.ArrayLike,
) -> np.ndarray:
    """The energy density after one increment by the trapezoidal rule, ``(n,)``.

    Args:
        energy: ``(n,)`` energy density at the start of the increment.
        stress_old: ``(n, 3, 3)`` stresses at its start (work-conjugate to the strain).
        stress_new: ``(n, 3, 3)`` stresses at its end.
        strain_old: ``(n, 3, 3)`` strains at its start.
        strain_new: ``(n, 3, 3)`` strains at its end.
    """
    energy = np.asarray(energy, dtype=float)
    arrays = [np.asarray(a, dtype=float) for a in (stress_old, stress_new, strain_old, strain_new)]
    for a in arrays:
        if energy.ndim != 1 or a.shape != (energy.size, 3, 3):
            raise ValueError(
                "trapezoidal_energy: energies (n,) and stresses and strains (n, 3, 3) are needed, "
                f"got {energy.shape} and {a.shape}"
            )
    s0, s1, e0, e1 = arrays
    return energy + 0.5 * np.einsum("nij,nij->n", s0 + s1, e1 - e0)


def green_lagrange_pair(
    deformation_gradient: npt.ArrayLike, first_piola: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """The second Piola-Kirchhoff stress ``F^-1 P`` and Green-Lagrange strain ``(F^T F - I)/2``.

    Args:
        deformation_gradient: ``(n, 3, 3)`` F.
        first_piola: ``(n, 3, 3)`` P.

    Returns:
        ``(S, E)``, each ``(n, 3, 3)``.
    """
    F = np.asarray(deformation_gradient, dtype=float)
    P = np.asarray(first_piola, dtype=float)
    if F.ndim != 3 or F.shape[1:] != (3, 3) or P.shape != F.shape:
        raise ValueError(
            f"green_lagrange_pair: F and P must have one shape (n, 3, 3), got {F.shape} and "
            f"{P.shape}"
        )
    S = np.linalg.solve(F, P)
    S = 0.5 * (S + np.swapaxes(S, 1, 2))  # symmetric up to round-off
    E = 0.5 * (np.einsum("nki,nkj->nij", F, F) - np.eye(3))
    return S, E
