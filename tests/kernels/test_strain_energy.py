"""The accumulated strain energy density (ccx's ENER) and the Green-Lagrange pair (method §36)."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.plasticity import (
    IsotropicHardening,
    elastic_matrix,
    mandel_from_tensor,
    return_map,
    tensor_from_mandel,
)
from dolfinx_ntf.kernels.strain_energy import green_lagrange_pair, trapezoidal_energy

E_MOD, NU = 5000.0, 0.3


def _symmetric(rng: np.random.Generator, n: int, scale: float) -> np.ndarray:
    a = rng.uniform(-scale, scale, (n, 3, 3))
    return 0.5 * (a + np.swapaxes(a, 1, 2))


def test_linear_elastic_path_gives_half_stress_strain() -> None:
    """Along any path of strains the trapezoidal rule of a linear law is S:E/2 at its end."""
    rng = np.random.default_rng(0)
    C = elastic_matrix(E_MOD, NU)
    strains = np.cumsum(_symmetric(rng, 7 * 5, 1e-3).reshape(7, 5, 3, 3), axis=0)
    energy = np.zeros(5)
    old_e = np.zeros((5, 3, 3))
    old_s = np.zeros((5, 3, 3))
    for e in strains:
        s = tensor_from_mandel(mandel_from_tensor(e) @ C.T)
        energy = trapezoidal_energy(energy, old_s, s, old_e, e)
        old_e, old_s = e, s
    half = 0.5 * np.einsum("nij,nij->n", old_s, old_e)
    np.testing.assert_allclose(energy, half, rtol=1e-12)


def _plastic_energy(increments: int) -> float:
    """Energy of a point pulled to 5 % uniaxial strain (lateral strain -nu e) in equal steps."""
    hardening = IsotropicHardening(yield_stress=[50.0, 100.0], plastic_strain=[0.0, 0.3])
    ep, alpha = np.zeros((1, 6)), np.zeros(1)
    energy, old_s, old_e = np.zeros(1), np.zeros((1, 3, 3)), np.zeros((1, 3, 3))
    for t in np.linspace(0.0, 0.05, increments + 1)[1:]:
        e = np.diag([t, -0.4 * t, -0.4 * t])[None]
        result = return_map(mandel_from_tensor(e), ep, alpha, E_MOD, NU, hardening)
        ep, alpha = result.plastic_strain, result.equivalent_plastic_strain
        s = tensor_from_mandel(result.stress)
        energy = trapezoidal_energy(energy, old_s, s, old_e, e)
        old_s, old_e = s, e
    return float(energy[0])


def test_plastic_path_converges() -> None:
    """Past yield the rule is not exact; its error shrinks as the steps do (measured 2.4 times
    per halving here: the increment holding the onset of yield is first order)."""
    coarse, fine, finer, reference = (_plastic_energy(n) for n in (10, 20, 40, 2560))
    ratio = (coarse - reference) / (fine - reference)
    assert abs(coarse - reference) > 1e-4 * reference  # not exact on a yielding path
    assert 2.0 < ratio < 4.5, ratio
    assert abs(finer - reference) < abs(fine - reference) / 2.0


def test_green_lagrange_pair_of_st_venant_kirchhoff() -> None:
    """P = F S of a St.Venant-Kirchhoff S = C E gives back S and E = (F^T F - I)/2."""
    rng = np.random.default_rng(1)
    F = np.eye(3) + rng.uniform(-0.2, 0.2, (6, 3, 3))
    E = 0.5 * (np.einsum("nki,nkj->nij", F, F) - np.eye(3))
    S = tensor_from_mandel(mandel_from_tensor(E) @ elastic_matrix(E_MOD, NU).T)
    second, green = green_lagrange_pair(F, F @ S)
    np.testing.assert_allclose(second, S, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(green, E, rtol=1e-12, atol=1e-15)


def test_bad_shapes_are_refused() -> None:
    with pytest.raises(ValueError, match="trapezoidal_energy"):
        trapezoidal_energy(np.zeros(2), *(np.zeros((3, 3, 3)),) * 4)
    with pytest.raises(ValueError, match="trapezoidal_energy"):
        trapezoidal_energy(np.zeros((2, 1)), *(np.zeros((2, 3, 3)),) * 4)
    with pytest.raises(ValueError, match="green_lagrange_pair"):
        green_lagrange_pair(np.zeros((2, 3, 3)), np.zeros((2, 3, 2)))
