"""Exact integration of the modal equations (kernels/modal_integration.py) against closed forms."""

import numpy as np
import pytest

from dolfinx_ntf.kernels.modal_integration import (
    increment_propagator,
    modal_increment,
    rayleigh_modal_damping,
)


def _step_response(omega: float, zeta: float, force: float, t: np.ndarray) -> tuple:
    """``q, q'`` of ``q'' + 2 zeta omega q' + omega^2 q = force`` from rest (step load)."""
    static = force / omega**2
    if zeta < 1.0:
        wd = omega * np.sqrt(1.0 - zeta**2)
        decay = np.exp(-zeta * omega * t)
        q = static * (1.0 - decay * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t)))
        v = static * decay * (omega**2 / wd) * np.sin(wd * t)
    elif zeta == 1.0:
        decay = np.exp(-omega * t)
        q = static * (1.0 - decay * (1.0 + omega * t))
        v = static * decay * omega**2 * t
    else:
        root = omega * np.sqrt(zeta**2 - 1.0)
        s1, s2 = -zeta * omega + root, -zeta * omega - root
        q = static * (1.0 + (s2 * np.exp(s1 * t) - s1 * np.exp(s2 * t)) / (s1 - s2))
        v = static * s1 * s2 * (np.exp(s1 * t) - np.exp(s2 * t)) / (s1 - s2)
    return q, v


def _integrate(eigenvalues, damping, forces, sizes):
    """Modal states after each increment of ``sizes`` under ``forces(t)`` (linear in between)."""
    q = np.zeros(len(eigenvalues))
    v = np.zeros(len(eigenvalues))
    t, out = 0.0, []
    for dt in sizes:
        P = increment_propagator(eigenvalues, damping, dt)
        q, v = modal_increment(P, q, v, forces(t), forces(t + dt), dt)
        t += dt
        out.append((t, q.copy(), v.copy()))
    return out


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.9, 1.0, 3.0])
def test_damped_oscillator_under_a_step_load_matches_the_closed_form(zeta):
    """Under-, critically and over-damped: exact at every increment end, any increment size."""
    omega, force = np.array([3.0, 7.5]), 2.0
    damping = 2.0 * zeta * omega
    sizes = [0.37, 0.05, 1.3, 0.37, 0.002, 2.0]
    for t, q, v in _integrate(omega**2, damping, lambda t: np.full(2, force), sizes):
        for i in range(2):
            q_exact, v_exact = _step_response(omega[i], zeta, force, np.array(t))
            assert q[i] == pytest.approx(q_exact, rel=1e-10, abs=1e-13)
            assert v[i] == pytest.approx(v_exact, rel=1e-10, abs=1e-12)


def test_a_linear_load_is_integrated_exactly_whatever_the_increments():
    """Undamped, ``f = r t``: ``q = (r / omega^2) (t - sin(omega t) / omega)``."""
    omega, rate = 4.0, 0.7

    def exact(t):
        return rate / omega**2 * (t - np.sin(omega * t) / omega)

    coarse = _integrate([omega**2], [0.0], lambda t: np.array([rate * t]), [0.9] * 5)
    fine = _integrate([omega**2], [0.0], lambda t: np.array([rate * t]), [0.01] * 450)
    assert coarse[-1][1][0] == pytest.approx(exact(4.5), rel=1e-11)
    assert fine[-1][1][0] == pytest.approx(exact(4.5), rel=1e-9)
    # a load that changes slope inside an increment is not linear there: not exact
    kinked = _integrate([omega**2], [0.0], lambda t: np.array([min(t, 1.0)]), [1.5, 1.5])
    kinked_fine = _integrate([omega**2], [0.0], lambda t: np.array([min(t, 1.0)]), [0.5] * 6)
    assert abs(kinked[-1][1][0] - kinked_fine[-1][1][0]) > 1e-3 * abs(kinked_fine[-1][1][0])


def test_rayleigh_damping_gives_ccx_damping_ratios():
    """``zeta = alpha / (2 omega) + beta omega / 2`` (ccx manual, *MODAL DAMPING)."""
    omega = np.array([82323.46, 483416.6])
    c = rayleigh_modal_damping(omega**2, 15000.0, 2e-7)
    zeta = c / (2 * omega)
    np.testing.assert_allclose(zeta, 15000.0 / (2 * omega) + 2e-7 * omega / 2, rtol=1e-14)
    # a rigid mode (omega = 0) is damped by alpha alone
    assert rayleigh_modal_damping([0.0], 2.0, 5.0)[0] == 2.0


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="increment must be finite and > 0"):
        increment_propagator([1.0], [0.0], 0.0)
    with pytest.raises(ValueError, match="modal damping must be finite and >= 0"):
        increment_propagator([1.0], [-0.1], 1.0)
    with pytest.raises(ValueError, match="non-finite"):
        rayleigh_modal_damping([np.nan], 1.0, 0.0)
