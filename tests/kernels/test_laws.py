"""Tests of the pressure-overclosure laws, friction data and surface interactions (pure numpy)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from dolfinx_ntf.kernels.laws import (
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    SurfaceInteraction,
    TabularLaw,
)

E_CAP = math.exp(23.0)


def _central_fd(func, x: np.ndarray, h: float) -> np.ndarray:
    return (func(x + h) - func(x - h)) / (2.0 * h)


# ----------------------------------------------------------------------------- exponential


def test_exponential_values():
    law = ExponentialLaw(c0=0.2, p0=3.0)
    assert law.beta == pytest.approx(math.log(100.0) / 0.2, rel=1e-15)
    p = law.pressure([0.0, -0.2, 0.1])
    np.testing.assert_allclose(p, [3.0, 0.03, 3.0 * 10.0], rtol=1e-13)
    np.testing.assert_allclose(law.pressure_derivative(0.0), law.beta * 3.0, rtol=1e-14)


def test_exponential_derivatives_fd():
    law = ExponentialLaw(c0=0.5, p0=2.0)
    d = np.linspace(-1.0, 0.5, 7)
    np.testing.assert_allclose(
        law.pressure_derivative(d), _central_fd(law.pressure, d, 1e-6), rtol=1e-7
    )
    area = np.array([0.1, 0.5, 1.0, 2.0, 3.0, 0.7, 0.2])
    force, dforce = law.spring_force(d, area)
    np.testing.assert_allclose(force, area * law.pressure(d), rtol=1e-13)
    fd = _central_fd(lambda x: law.spring_force(x, area)[0], d, 1e-6)
    np.testing.assert_allclose(dforce, fd, rtol=1e-7)


def test_exponential_cap():
    law = ExponentialLaw(c0=1.0, p0=1.0)
    area = 2.0
    # exponent beta d + ln(A p0) = 23 at d = (23 - ln 2)/beta
    d_cap = (23.0 - math.log(area)) / law.beta
    force, dforce = law.spring_force([0.5 * d_cap, 2.0 * d_cap, 10.0 * d_cap], area)
    assert force[0] == pytest.approx(area * law.pressure(0.5 * d_cap), rel=1e-13)
    assert dforce[0] == pytest.approx(law.beta * force[0], rel=1e-13)
    np.testing.assert_allclose(force[1:], E_CAP, rtol=1e-14)
    # ccx's derivative beta' F with beta' = (ln(A p0) - 23)/g, g = -d
    for k, d in ((1, 2.0 * d_cap), (2, 10.0 * d_cap)):
        beta_cap = (math.log(area) - 23.0) / (-d)
        assert dforce[k] == pytest.approx(beta_cap * E_CAP, rel=1e-13)
        assert dforce[k] < law.beta * E_CAP
    # energy uses the capped force
    np.testing.assert_allclose(law.energy(10.0 * d_cap, area), E_CAP / law.beta, rtol=1e-14)


def test_exponential_cap_huge_area_at_zero_gap():
    law = ExponentialLaw(c0=1.0, p0=1e6)
    area = 1e6  # A p0 = 1e12 > e^23
    force, dforce = law.spring_force([0.0, 1e-3, -1e-3], area)
    np.testing.assert_allclose(force, E_CAP, rtol=1e-14)
    assert np.all(np.isfinite(dforce))
    assert dforce[0] == pytest.approx(law.beta * E_CAP)
    log_ap0 = math.log(area * 1e6)
    assert dforce[1] == pytest.approx((log_ap0 - 23.0) / (-1e-3) * E_CAP, rel=1e-12)
    assert dforce[2] == pytest.approx((log_ap0 - 23.0) / 1e-3 * E_CAP, rel=1e-12)


def test_exponential_zero_p0_and_zero_area():
    law = ExponentialLaw(c0=1.0, p0=1e-31)
    force, dforce = law.spring_force([0.0, 5.0], 1.0)
    assert np.all(force == 0.0) and np.all(dforce == 0.0)
    assert np.all(law.pressure([0.0, 5.0]) == 0.0)
    assert np.all(law.energy([0.0, 5.0], 1.0) == 0.0)
    law = ExponentialLaw(c0=1.0, p0=1.0)
    force, dforce = law.spring_force([0.0, 1.0], [0.0, 1.0])
    assert force[0] == 0.0 and dforce[0] == 0.0
    assert force[1] == pytest.approx(100.0)


def test_exponential_cutoff_and_energy():
    law = ExponentialLaw(c0=0.3, p0=2.0)
    np.testing.assert_array_equal(law.cutoff([0.0, 1.0, 4.0]), [0.3, 0.3, 0.3])
    d = np.array([-0.1, 0.0, 0.2])
    area = np.array([1.0, 2.0, 0.5])
    np.testing.assert_allclose(
        law.energy(d, area), area * 2.0 * np.exp(law.beta * d) / law.beta, rtol=1e-13
    )


# ----------------------------------------------------------------------------- linear


def test_linear_values():
    law = LinearLaw(slope=100.0, tension=2.0, c0=1e-2)
    eps = math.pi * 2.0 / 100.0
    assert law.epsilon == pytest.approx(eps)
    assert law.pressure(0.0) == 0.0
    # d = eps: K eps (1/2 + 1/4)
    assert law.pressure(eps) == pytest.approx(100.0 * eps * 0.75, rel=1e-14)
    assert law.pressure(-eps) == pytest.approx(-100.0 * eps * 0.25, rel=1e-14)
    # asymptotes: p ~ K d - tension for d >> eps, p -> -tension for d << -eps
    assert law.pressure(1e4) == pytest.approx(100.0 * 1e4 - 2.0, rel=1e-12)
    assert law.pressure(-1e6) == pytest.approx(-2.0, rel=1e-6)
    assert law.pressure_derivative(0.0) == pytest.approx(50.0, rel=1e-15)
    assert law.pressure_derivative(1e8) == pytest.approx(100.0, rel=1e-8)


def test_linear_derivatives_fd():
    law = LinearLaw(slope=1e3, tension=5.0)
    d = law.epsilon * np.array([-30.0, -2.0, -0.5, 0.0, 0.3, 1.0, 7.0, 100.0])
    h = 1e-5 * law.epsilon
    np.testing.assert_allclose(
        law.pressure_derivative(d), _central_fd(law.pressure, d, h), rtol=1e-7, atol=1e-9
    )
    area = np.linspace(0.5, 2.0, d.size)
    force, dforce = law.spring_force(d, area)
    np.testing.assert_allclose(force, area * law.pressure(d), rtol=1e-14)
    fd = _central_fd(lambda x: law.spring_force(x, area)[0], d, h)
    np.testing.assert_allclose(dforce, fd, rtol=1e-7, atol=1e-9)


def test_linear_cutoff_and_energy():
    law = LinearLaw(slope=10.0, tension=1.0, c0=2e-3)
    np.testing.assert_allclose(law.cutoff([0.0, 4.0, 0.25]), [1e-10, 4e-3, 1e-3], rtol=1e-15)
    d = np.array([-0.5, 0.0, 0.2])
    area = np.array([1.0, 3.0, 2.0])
    force, _ = law.spring_force(d, area)
    np.testing.assert_allclose(law.energy(d, area), 0.5 * force * d, rtol=1e-15)
    assert law.energy(0.2, 2.0) > 0.0


def test_linear_ccx_defaults():
    law = LinearLaw.with_ccx_defaults(210000.0)
    assert law.slope == 50.0 * 210000.0
    assert law.tension == pytest.approx(3.0)
    assert law.c0 == 1e-3
    with pytest.warns(UserWarning) as caught:
        law = LinearLaw.with_ccx_defaults(210000.0, slope=-1.0, tension=0.0, c0=-2.0)
    assert (law.slope, law.tension, law.c0) == (50.0 * 210000.0, 3.0, 1e-3)
    # Negative values are named (zero asks for the default, as in a deck).
    assert [str(w.message).split(";")[0] for w in caught] == [
        "LinearLaw.with_ccx_defaults: slope = -1.0 is negative",
        "LinearLaw.with_ccx_defaults: c0 = -2.0 is negative",
    ]
    law = LinearLaw.with_ccx_defaults(210000.0, slope=1e6, tension=7.0, c0=0.01)
    assert (law.slope, law.tension, law.c0) == (1e6, 7.0, 0.01)


# ----------------------------------------------------------------------------- tabular


def _table() -> TabularLaw:
    return TabularLaw(pressures=[0.0, 10.0, 30.0, 40.0], overclosures=[0.0, 1.0, 2.0, 4.0])


def test_tabular_values_and_extrapolation():
    law = _table()
    d = np.array([-5.0, 0.0, 0.5, 1.0, 1.5, 3.0, 4.0, 9.0])
    np.testing.assert_allclose(law.pressure(d), [0.0, 0.0, 5.0, 10.0, 20.0, 35.0, 40.0, 40.0])
    np.testing.assert_allclose(
        law.pressure_derivative(d), [0.0, 10.0, 10.0, 20.0, 20.0, 5.0, 0.0, 0.0]
    )
    law = TabularLaw(pressures=[2.0, 3.0], overclosures=[-1.0, 1.0])
    assert law.pressure(-7.0) == 2.0 and law.pressure(7.0) == 3.0


def test_tabular_derivative_fd_away_from_kinks():
    law = _table()
    d = np.array([-2.0, 0.3, 0.7, 1.4, 2.5, 3.9, 6.0])
    np.testing.assert_allclose(
        law.pressure_derivative(d), _central_fd(law.pressure, d, 1e-6), rtol=1e-6, atol=1e-9
    )
    area = 1.7
    force, dforce = law.spring_force(d, area)
    np.testing.assert_allclose(force, area * law.pressure(d))
    fd = _central_fd(lambda x: law.spring_force(x, area)[0], d, 1e-6)
    np.testing.assert_allclose(dforce, fd, rtol=1e-6, atol=1e-9)


def test_tabular_cutoff():
    law = _table()
    np.testing.assert_allclose(law.cutoff([0.0, 4.0]), [1e-10, 2e-3], rtol=1e-15)
    assert law.c0 == 1e-3


def test_tabular_energy():
    law = _table()
    area = 2.0
    # inside: trapezoidal integral from d_1 = 0
    assert law.energy(0.5, area) == pytest.approx(area * 0.5 * 0.5 * 5.0)
    assert law.energy(1.0, area) == pytest.approx(area * 5.0)
    assert law.energy(1.5, area) == pytest.approx(area * (5.0 + 0.5 * (10.0 + 20.0) / 2.0))
    full = 5.0 + 20.0 + 70.0
    assert law.energy(4.0, area) == pytest.approx(area * full)
    # beyond d_N: ccx adds (p_N - d_N) p_N, independent of d
    quirk = area * (full + (40.0 - 4.0) * 40.0)
    np.testing.assert_allclose(law.energy([4.5, 100.0], area), [quirk, quirk])
    # below d_1: integral of the constant extrapolation
    law = TabularLaw(pressures=[1.0, 2.0], overclosures=[0.0, 1.0])
    assert law.energy(-0.5, 3.0) == pytest.approx(3.0 * 1.0 * -0.5)
    # the energy is the integral of the force inside the table
    law = _table()
    d = np.array([0.3, 1.2, 2.0, 3.3])
    fd = _central_fd(lambda x: law.energy(x, area), d, 1e-6)
    np.testing.assert_allclose(fd, law.spring_force(d, area)[0], rtol=1e-6)


def test_tabular_nudge_and_errors():
    law = TabularLaw(pressures=[0.0, 1.0, 2.0, 3.0], overclosures=[0.0, 0.0, 0.5e-10, 1.0])
    np.testing.assert_allclose(law.overclosures, [0.0, 1e-10, 2e-10, 1.0], rtol=1e-12)
    assert np.all(np.diff(law.overclosures) >= 1e-10 * (1 - 1e-12))
    with pytest.raises(ValueError, match="point 2"):
        TabularLaw(pressures=[0.0, 1.0, 2.0], overclosures=[0.0, 1.0, 0.5])
    with pytest.raises(ValueError, match="at least 2"):
        TabularLaw(pressures=[1.0], overclosures=[0.0])
    with pytest.raises(ValueError, match="3 pressures but 2 overclosures"):
        TabularLaw(pressures=[0.0, 1.0, 2.0], overclosures=[0.0, 1.0])
    with pytest.raises(ValueError, match="pressures must be finite"):
        TabularLaw(pressures=[0.0, np.nan], overclosures=[0.0, 1.0])
    with pytest.raises(ValueError, match="overclosures must be finite"):
        TabularLaw(pressures=[0.0, 1.0], overclosures=[0.0, np.inf])
    with pytest.raises(ValueError, match="1-D"):
        TabularLaw(pressures=[[0.0, 1.0]], overclosures=[[0.0, 1.0]])
    # negative pressures are accepted (CalculiX says nothing about them)
    assert TabularLaw(pressures=[-1.0, 1.0], overclosures=[0.0, 1.0]).pressure(0.5) == 0.0
    with pytest.raises(ValueError):
        law.overclosures[0] = 5.0  # read-only


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    ("factory", "match"),
    [
        (lambda: ExponentialLaw(c0=0.0, p0=1.0), r"ExponentialLaw: c0 must be > 0, got 0\.0"),
        (lambda: ExponentialLaw(c0=-1.0, p0=1.0), r"ExponentialLaw: c0 must be > 0, got -1\.0"),
        (lambda: ExponentialLaw(c0=1.0, p0=-2.0), r"ExponentialLaw: p0 must be >= 0, got -2\.0"),
        (lambda: ExponentialLaw(c0=np.nan, p0=1.0), r"ExponentialLaw: c0 must be finite"),
        (lambda: ExponentialLaw(c0=1.0, p0=np.inf), r"ExponentialLaw: p0 must be finite"),
        (lambda: ExponentialLaw(c0="1", p0=1.0), r"ExponentialLaw: c0 must be a real number"),
        (lambda: LinearLaw(slope=0.0, tension=1.0), r"LinearLaw: slope must be > 0, got 0\.0"),
        (lambda: LinearLaw(slope=1.0, tension=1e-31), r"LinearLaw: tension must be >= 1e-30"),
        (lambda: LinearLaw(slope=1.0, tension=-1.0), r"LinearLaw: tension .* got -1\.0"),
        (lambda: LinearLaw(slope=1.0, tension=1.0, c0=0.0), r"LinearLaw: c0 must be > 0"),
        (lambda: LinearLaw(slope=np.inf, tension=1.0), r"LinearLaw: slope must be finite"),
        (lambda: LinearLaw(slope=None, tension=1.0), r"LinearLaw: slope must be a real number"),
        (
            lambda: LinearLaw.with_ccx_defaults(0.0),
            r"LinearLaw.with_ccx_defaults: youngs_modulus must be > 0, got 0\.0",
        ),
        (
            lambda: LinearLaw.with_ccx_defaults(1.0, slope=np.nan),
            r"LinearLaw.with_ccx_defaults: slope must be finite",
        ),
        (lambda: Friction(mu=0.0, stick_slope=1.0), r"Friction: mu must be > 0, got 0\.0"),
        (lambda: Friction(mu=0.3, stick_slope=-1.0), r"Friction: stick_slope must be > 0"),
        (lambda: Friction(mu=np.nan, stick_slope=1.0), r"Friction: mu must be finite"),
        (
            lambda: Friction.with_ccx_defaults(0.3, None, -5.0),
            r"Friction.with_ccx_defaults: youngs_modulus must be > 0, got -5\.0",
        ),
        (lambda: Friction.with_ccx_defaults(-0.3, 1.0, 5.0), r"Friction: mu must be > 0"),
        (lambda: SurfaceInteraction(law="hard"), r"law must be a PressureOverclosureLaw"),
        (
            lambda: SurfaceInteraction(law=LinearLaw(1.0, 1.0), friction=0.3),
            r"friction must be a Friction or None",
        ),
    ],
)
def test_parameter_errors(factory, match):
    with pytest.raises(ValueError, match=match):
        factory()


@pytest.mark.parametrize(
    "law",
    [ExponentialLaw(1.0, 1.0), LinearLaw(1.0, 1.0), _table()],
    ids=["exp", "lin", "tab"],
)
def test_evaluation_errors(law: PressureOverclosureLaw):
    name = type(law).__name__
    with pytest.raises(ValueError, match=rf"{name}: area must be >= 0, got -1\.0 at index \(1,\)"):
        law.spring_force([0.0, 0.0], [1.0, -1.0])
    with pytest.raises(ValueError, match=rf"{name}: overclosure d must be finite.*index \(2,\)"):
        law.pressure([0.0, 1.0, np.nan])
    with pytest.raises(ValueError, match=rf"{name}: overclosure d must be finite"):
        law.energy([np.inf], [1.0])
    with pytest.raises(ValueError, match=rf"{name}: area must be finite"):
        law.cutoff([np.nan])
    with pytest.raises(ValueError, match="do not broadcast"):
        law.spring_force(np.zeros(3), np.ones(2))


@pytest.mark.parametrize(
    "law",
    [ExponentialLaw(0.1, 2.0), LinearLaw(50.0, 0.1), _table()],
    ids=["exp", "lin", "tab"],
)
def test_vectorized_shapes(law: PressureOverclosureLaw):
    d = np.linspace(-0.1, 1.0, 6).reshape(2, 3)
    area = np.array([1.0, 2.0, 3.0])
    force, dforce = law.spring_force(d, area)
    assert force.shape == dforce.shape == (2, 3)
    assert law.energy(d, area).shape == (2, 3)
    assert law.cutoff(area).shape == (3,)
    assert law.pressure(d).shape == law.pressure_derivative(d).shape == (2, 3)
    force_scalar, _ = law.spring_force(0.1, 2.0)
    assert np.ndim(force_scalar) == 0
    assert force_scalar == pytest.approx(2.0 * float(law.pressure(0.1)))


# ----------------------------------------------------------------------------- friction


def test_friction_defaults_and_interaction():
    friction = Friction(mu=0.2, stick_slope=1e4)
    assert (friction.mu, friction.stick_slope) == (0.2, 1e4)
    with pytest.warns(UserWarning, match="E/2"):
        friction = Friction.with_ccx_defaults(0.2, None, 210000.0)
    assert friction.stick_slope == 105000.0
    with pytest.warns(UserWarning):
        assert Friction.with_ccx_defaults(0.2, -3.0, 10.0).stick_slope == 5.0
    friction = Friction.with_ccx_defaults(0.2, 7.0, 10.0)
    assert friction.stick_slope == 7.0
    law = LinearLaw(1.0, 1.0)
    interaction = SurfaceInteraction(law)
    assert interaction.friction is None and interaction.law is law
    assert SurfaceInteraction(law, friction).friction is friction
