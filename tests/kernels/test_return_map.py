"""Tests of the J2 return map and its consistent tangent (kernels/plasticity), numpy only."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.plasticity import (
    DEVIATOR,
    IDENTITY,
    IsotropicHardening,
    elastic_matrix,
    mandel_from_tensor,
    return_map,
    tensor_from_mandel,
)

E, NU = 200e3, 0.3
MU = E / (2 * (1 + NU))
TABLE = IsotropicHardening((250.0, 300.0, 320.0), (0.0, 0.002, 0.01))
HARDENINGS = {
    "table": TABLE,
    "table-linear-beyond": IsotropicHardening(
        (250.0, 300.0, 320.0), (0.0, 0.002, 0.01), beyond="linear"
    ),
    "linear": IsotropicHardening.linear(250.0, 20e3),
    "perfect": IsotropicHardening.linear(250.0, 0.0),
    "softening": IsotropicHardening((250.0, 200.0), (0.0, 0.01), "linear"),
}


def _states(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random strains around yield, deviatoric plastic strains and alphas across the table."""
    rng = np.random.default_rng(seed)
    scale = rng.uniform(0.2, 4.0, n)[:, None] * 250.0 / E
    strain = rng.normal(size=(n, 6)) * scale
    plastic = rng.normal(size=(n, 6)) * 1e-3 @ DEVIATOR
    alpha = rng.uniform(0.0, 0.015, n)
    return strain, plastic, alpha


def _mises(stress: np.ndarray) -> np.ndarray:
    return np.sqrt(1.5) * np.linalg.norm(stress @ DEVIATOR, axis=1)


def test_mandel_round_trip() -> None:
    """Mandel vectors contract like the tensors: a . b = A : B."""
    rng = np.random.default_rng(1)
    A = rng.normal(size=(5, 3, 3))
    A = A + np.swapaxes(A, 1, 2)
    B = rng.normal(size=(5, 3, 3))
    B = B + np.swapaxes(B, 1, 2)
    np.testing.assert_allclose(tensor_from_mandel(mandel_from_tensor(A)), A)
    a, b = mandel_from_tensor(A), mandel_from_tensor(B)
    np.testing.assert_allclose((a * b).sum(axis=1), np.einsum("nij,nij->n", A, B))


@pytest.mark.parametrize("name", HARDENINGS)
def test_return_is_on_the_yield_surface(name: str) -> None:
    """Plastic points end on sigma_y(alpha_n+1) with the flow along the deviator; elastic ones
    keep the trial stress and the history."""
    hardening = HARDENINGS[name]
    strain, plastic, alpha = _states()
    result = return_map(strain, plastic, alpha, E, NU, hardening)
    yielded = result.plastic
    assert 0 < yielded.sum() < yielded.size  # both kinds of points are tested
    sigma_y, _ = hardening(result.equivalent_plastic_strain)
    np.testing.assert_allclose(_mises(result.stress)[yielded], sigma_y[yielded], rtol=1e-12)
    assert np.all(_mises(result.stress)[~yielded] <= sigma_y[~yielded] * (1 + 1e-12))
    trial = (strain - plastic) @ elastic_matrix(E, NU)
    np.testing.assert_array_equal(result.stress[~yielded], trial[~yielded])
    np.testing.assert_array_equal(result.equivalent_plastic_strain[~yielded], alpha[~yielded])
    # stress = C (eps - eps_p_new); the plastic strain increment is deviatoric, of norm
    # sqrt(3/2) dg
    np.testing.assert_allclose(
        result.stress, (strain - result.plastic_strain) @ elastic_matrix(E, NU), atol=1e-9
    )
    increment = result.plastic_strain - plastic
    np.testing.assert_allclose(increment @ IDENTITY, 0.0, atol=1e-15)
    np.testing.assert_allclose(
        np.linalg.norm(increment, axis=1),
        np.sqrt(1.5) * (result.equivalent_plastic_strain - alpha),
        atol=1e-15,
    )
    assert np.all(result.equivalent_plastic_strain >= alpha)


@pytest.mark.parametrize("name", HARDENINGS)
def test_tangent_against_finite_differences(name: str) -> None:
    """The algorithmic tangent is the derivative of the returned stress (central differences)."""
    hardening = HARDENINGS[name]
    strain, plastic, alpha = _states(200, seed=2)
    result = return_map(strain, plastic, alpha, E, NU, hardening)
    assert 0 < result.plastic.sum() < result.plastic.size
    h = 1e-9
    worst = 0.0
    for k in range(6):
        up, down = strain.copy(), strain.copy()
        up[:, k] += h
        down[:, k] -= h
        fd = (
            return_map(up, plastic, alpha, E, NU, hardening).stress
            - return_map(down, plastic, alpha, E, NU, hardening).stress
        ) / (2 * h)
        worst = max(worst, np.abs(fd - result.tangent[:, :, k]).max())
    assert worst < 1e-6 * E
    np.testing.assert_allclose(result.tangent, np.swapaxes(result.tangent, 1, 2), atol=1e-9)


def test_uniaxial_linear_hardening_closed_form() -> None:
    """Uniaxial stress path: sigma = E eps up to sigma_y0, then the tangent modulus E H/(E + H).

    The lateral strains that keep the lateral stresses at zero are found by Newton with the
    algorithmic tangent itself, increment by increment from the committed history.
    """
    sigma_y0, H = 250.0, 20e3
    hardening = IsotropicHardening.linear(sigma_y0, H)
    plastic, alpha = np.zeros((1, 6)), np.zeros(1)
    strain = np.zeros((1, 6))
    for eps_x in np.linspace(0.0, 6 * sigma_y0 / E, 13)[1:]:
        strain[0, 0] = eps_x
        for _ in range(20):  # lateral strains: sigma_yy = sigma_zz = 0
            result = return_map(strain, plastic, alpha, E, NU, hardening)
            lateral = result.stress[0, 1:3]
            if np.abs(lateral).max() < 1e-10 * sigma_y0:
                break
            strain[0, 1:3] -= np.linalg.solve(result.tangent[0, 1:3, 1:3], lateral)
        plastic, alpha = result.plastic_strain, result.equivalent_plastic_strain
        if eps_x <= sigma_y0 / E:
            expected = E * eps_x
        else:
            expected = sigma_y0 + E * H / (E + H) * (eps_x - sigma_y0 / E)
        np.testing.assert_allclose(result.stress[0, 0], expected, rtol=1e-12)
        np.testing.assert_allclose(
            alpha[0], max(0.0, (expected - sigma_y0) / H), rtol=1e-10, atol=1e-16
        )


def test_table_lookup_and_kinks() -> None:
    """Piecewise linear, the right slope at a table point, constant (or linear) beyond."""
    stress, slope = TABLE([0.0, 0.001, 0.002, 0.006, 0.02])
    np.testing.assert_allclose(stress, [250.0, 275.0, 300.0, 310.0, 320.0])
    np.testing.assert_allclose(slope, [25e3, 25e3, 2.5e3, 2.5e3, 0.0])
    linear = HARDENINGS["table-linear-beyond"]
    np.testing.assert_allclose(linear([0.02])[0], [320.0 + 2.5e3 * 0.01])


def test_return_across_table_points() -> None:
    """A return that crosses table points lands on the right piece (closed form per piece)."""
    # Pure shear gamma: q_tr = sqrt(3) mu gamma, and q_tr - 3 mu dg = sigma_y(alpha_0 + dg): pick
    # the end state (alpha_0, dg) and shear by the gamma that reaches it.
    for alpha0, dg in ((0.0, 0.0012), (0.001, 0.0006), (0.0, 0.002), (0.003, 0.02), (0.0, 0.05)):
        sigma_y = np.interp(alpha0 + dg, TABLE.plastic_strain, TABLE.yield_stress)  # flat beyond
        gamma = (sigma_y + 3 * MU * dg) / (np.sqrt(3) * MU)
        strain = np.zeros((1, 6))
        strain[0, 3] = np.sqrt(2) * gamma / 2
        result = return_map(strain, np.zeros((1, 6)), [alpha0], E, NU, TABLE)
        assert result.plastic[0]
        np.testing.assert_allclose(_mises(result.stress)[0], sigma_y, rtol=1e-12)
        np.testing.assert_allclose(result.equivalent_plastic_strain[0] - alpha0, dg, rtol=1e-10)


@pytest.mark.parametrize(
    ("stress", "strain", "message"),
    [
        ((250.0, 300.0), (0.1, 0.2), "first line's plastic strain must be 0"),
        ((250.0, 300.0), (0.0, 0.0), "line 2"),
        ((250.0, -1.0), (0.0, 0.1), "line 2 has -1.0"),
        ((250.0,), (0.0, 0.1), "same length"),
        ((250.0, np.nan), (0.0, 0.1), "finite"),
    ],
)
def test_bad_tables(stress, strain, message) -> None:
    """Tables that CalculiX would refuse (or that have no meaning) name the line."""
    with pytest.raises(ValueError, match=message):
        IsotropicHardening(stress, strain)


def test_bad_inputs() -> None:
    """Softening faster than -3 mu, mismatched shapes and bad elasticity are errors."""
    with pytest.raises(ValueError, match="exceed -3 mu"):
        return_map(
            np.zeros((1, 6)),
            np.zeros((1, 6)),
            np.zeros(1),
            E,
            NU,
            IsotropicHardening((250.0, 100.0), (0.0, 1e-4), beyond="linear"),  # -1.5e6 < -3 mu
        )
    with pytest.raises(ValueError, match="same number of points"):
        return_map(np.zeros((2, 6)), np.zeros((1, 6)), np.zeros(1), E, NU, TABLE)
    with pytest.raises(ValueError, match=r"nu < 0\.5"):
        return_map(np.zeros((1, 6)), np.zeros((1, 6)), np.zeros(1), E, 0.5, TABLE)
    with pytest.raises(ValueError, match="beyond"):
        IsotropicHardening((250.0, 300.0), (0.0, 0.1), beyond="quadratic")
