"""Simo's finite-strain J2 return (kernels/finite_plasticity), numpy only.

Its complex-step tangent against central differences of P, its small-strain limit (the additive
return map of kernels/plasticity), objectivity, a path through the table's
pieces and the bad arguments.
"""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.finite_plasticity import finite_return_map
from dolfinx_ntf.kernels.plasticity import (
    IsotropicHardening,
    mandel_from_tensor,
    return_map,
    tensor_from_mandel,
)

E, NU = 5000.0, 0.3
TABLE = IsotropicHardening((50.0, 80.0, 90.0), (0.0, 0.01, 0.05))
HARDENINGS = {
    "table": TABLE,
    "linear": IsotropicHardening.linear(50.0, 500.0),
    "perfect": IsotropicHardening.linear(50.0, 0.0),
}


def _states(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Random gradients near the identity past yield, committed histories with plastic strain."""
    rng = np.random.default_rng(seed)
    F = np.eye(3) + 0.03 * rng.standard_normal((n, 3, 3))
    G = np.eye(3) + 0.005 * rng.standard_normal((n, 3, 3))
    G /= np.cbrt(np.linalg.det(G))[:, None, None]  # isochoric plastic part
    cp_inv = np.linalg.inv(np.einsum("nki,nkj->nij", G, G))
    alpha = 0.02 * rng.random(n)
    return F, cp_inv, alpha


@pytest.mark.parametrize("name", sorted(HARDENINGS))
def test_tangent_against_central_differences(name: str) -> None:
    """dP/dF by complex steps equals central differences of P at elastic and plastic points."""
    hardening = HARDENINGS[name]
    F, cp_inv, alpha = _states(60)
    F[:10] = np.eye(3) + 1e-4 * (F[:10] - np.eye(3))  # elastic points
    result = finite_return_map(F, cp_inv, alpha, E, NU, hardening)
    assert result.plastic[10:].any() and not result.plastic[:10].all()
    h = 1e-7
    worst = 0.0
    for k in range(3):
        for m in range(3):
            Fp, Fm = F.copy(), F.copy()
            Fp[:, k, m] += h
            Fm[:, k, m] -= h
            fd = (
                finite_return_map(Fp, cp_inv, alpha, E, NU, hardening).first_piola
                - finite_return_map(Fm, cp_inv, alpha, E, NU, hardening).first_piola
            ) / (2 * h)
            worst = max(worst, np.abs(fd - result.tangent[:, :, :, k, m]).max())
    assert worst < 1e-6 * E, worst


def test_small_strain_limit_is_the_additive_return() -> None:
    """For strains of 1e-6 past a tiny yield stress, P is the additive return's stress to 1e-5."""
    hardening = IsotropicHardening.linear(1e-3, 2.0)
    rng = np.random.default_rng(3)
    H = 1e-6 * rng.standard_normal((40, 3, 3))
    eps = 0.5 * (H + np.swapaxes(H, 1, 2))
    finite = finite_return_map(np.eye(3) + H, np.tile(np.eye(3), (40, 1, 1)), np.zeros(40), E,
                               NU, hardening)  # fmt: skip
    small = return_map(mandel_from_tensor(eps), np.zeros((40, 6)), np.zeros(40), E, NU, hardening)
    assert finite.plastic.all() and small.plastic.all()
    stress = tensor_from_mandel(small.stress)
    scale = np.abs(stress).max()
    assert np.abs(finite.cauchy - stress).max() < 1e-5 * scale
    np.testing.assert_allclose(finite.equivalent_plastic_strain, small.equivalent_plastic_strain,
                               rtol=1e-4)  # fmt: skip


def test_objective() -> None:
    """A rotation R F turns the Cauchy stress to R sigma R^T and keeps the history; elastic
    points keep their committed history. (Simo's update ``be = s / mu + tr(be_tr) / 3 I``, which
    ccx's results follow, keeps ``det be = 1`` to first order only: not tested.)"""
    F, cp_inv, alpha = _states(30, seed=1)
    angle = 0.7
    c, s = np.cos(angle), np.sin(angle)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    a = finite_return_map(F, cp_inv, alpha, E, NU, TABLE)
    b = finite_return_map(R @ F, cp_inv, alpha, E, NU, TABLE)
    assert a.plastic.any()
    np.testing.assert_allclose(b.cauchy, R @ a.cauchy @ R.T, atol=1e-10 * np.abs(a.cauchy).max())
    np.testing.assert_allclose(b.equivalent_plastic_strain, a.equivalent_plastic_strain, rtol=1e-12)
    values, vectors = np.linalg.eigh(np.linalg.inv(cp_inv[:10]))
    F[:10] = np.einsum("nik,nk,njk->nij", vectors, np.sqrt(values), vectors)  # be = I
    F[:10] *= 1.0 + 1e-4 * np.arange(10)[:, None, None]  # and a small volume change
    c = finite_return_map(F, cp_inv, alpha, E, NU, TABLE)
    assert not c.plastic[:10].any()
    np.testing.assert_allclose(c.inverse_plastic_metric[:10], cp_inv[:10], rtol=1e-12)
    np.testing.assert_array_equal(c.equivalent_plastic_strain[:10], alpha[:10])


def test_uniaxial_path_meets_the_table() -> None:
    """Pulled uniaxially (lateral stress zero by a scalar Newton) to 20 % in many increments: the
    Mises Cauchy stress stays on the table's yield curve at every plastic increment."""
    cp_inv, alpha, lateral = np.eye(3)[None], np.zeros(1), 1.0
    for step in range(1, 101):
        stretch = 1 + 0.2 * step / 100
        for _ in range(30):
            F = np.diag([stretch, lateral, lateral])[None]
            result = finite_return_map(F, cp_inv, alpha, E, NU, TABLE)
            if abs(result.cauchy[0, 1, 1]) < 1e-10:
                break
            # dP_22/dF_22 + dP_22/dF_33, with P_22 = sigma_22 J / lateral
            slope = result.tangent[0, 1, 1, 1, 1] + result.tangent[0, 1, 1, 2, 2]
            lateral -= result.first_piola[0, 1, 1] / slope
        cp_inv, alpha = result.inverse_plastic_metric, result.equivalent_plastic_strain
        if result.plastic[0]:
            expected, _ = TABLE(alpha)
            assert result.cauchy[0, 0, 0] == pytest.approx(expected[0], rel=1e-10)
    assert alpha[0] > 0.05  # past the table's last line


def test_bad_arguments() -> None:
    F, cp_inv, alpha = _states(2)
    with pytest.raises(ValueError, match="same number of points"):
        finite_return_map(F, cp_inv[:1], alpha, E, NU, TABLE)
    with pytest.raises(ValueError, match=r"nu < 0\.5"):
        finite_return_map(F, cp_inv, alpha, E, 0.5, TABLE)
    bad = F.copy()
    bad[1] = np.diag([1.0, 1.0, -1.0])
    with pytest.raises(ValueError, match=r"det F = -1 <= 0 at point 1"):
        finite_return_map(bad, cp_inv, alpha, E, NU, TABLE)
