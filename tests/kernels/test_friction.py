"""Friction of the spring elements (kernels.friction through evaluate_springs), pure numpy."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.spring_differences import nodal_differences, relative_error

from dolfinx_ntf.kernels.faces import FACE_TYPES, face_points, face_tangents
from dolfinx_ntf.kernels.friction import FrictionInput, output_tangents, tangential_forces
from dolfinx_ntf.kernels.laws import ExponentialLaw, LinearLaw
from dolfinx_ntf.kernels.springs import evaluate_springs

SIZE = 2.0
LINEAR = LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3)
EXPONENTIAL = ExponentialLaw(c0=0.2, p0=3.0)
CASES = [("tri3", 0.0), ("quad4", 0.0), ("quad4", 0.15), ("tri6", 0.1), ("quad8", 0.1)]
CASE_IDS = [f"{name}-{'warped' if warp else 'flat'}" for name, warp in CASES]


def _rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _springs(name, warp, num, seed):
    """Reference nodes X, displacements u (x = X + u) of penetrating springs, and a start state."""
    ft = FACE_TYPES[name]
    rng = np.random.default_rng(seed)
    params = ft.node_parameters * (SIZE if ft.is_triangle else SIZE / 2)
    coords = np.zeros((num, ft.num_nodes, 3))
    coords[:, :, :2] = params + 0.08 * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes, 2))
    coords[:, :, 2] = warp * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes))
    rot = np.stack([_rotation(rng) for _ in range(num)])
    coords = np.einsum("nij,nkj->nki", rot, coords) + rng.uniform(-5, 5, (num, 1, 3))
    if ft.is_triangle:
        xi = 0.2 + 0.3 * rng.uniform(size=(num, 2))
    else:
        xi = rng.uniform(-0.5, 0.5, (num, 2))
    t1, t2 = face_tangents(ft, coords, xi)
    m = np.cross(t1, t2)
    n = m / np.linalg.norm(m, axis=1)[:, None]
    depth = rng.uniform(0.002, 0.05, num) * SIZE
    slave = face_points(ft, coords, xi) - depth[:, None] * n
    x = np.concatenate([coords, slave[:, None]], axis=1)
    u = 0.05 * SIZE * rng.uniform(-1, 1, x.shape)
    areas = rng.uniform(0.5, 2.0, num)
    a_start = 0.05 * SIZE * rng.uniform(-1, 1, (num, 3))
    t_start = 0.01 * SIZE * rng.uniform(-1, 1, (num, 3))
    slip_start = 0.01 * SIZE * rng.uniform(-1, 1, (num, 3))
    return ft, x, u, areas, (a_start, t_start, slip_start)


def _data(u, start, mu, slope, **kwargs):
    return FrictionInput(u, *start, mu=mu, stick_slope=slope, **kwargs)


def _evaluate(ft, x, areas, law, data, **kwargs):
    return evaluate_springs(ft, x[:, :-1], x[:, -1], areas, law, friction=data, **kwargs)


def _finite_difference(ft, x, u, areas, law, data, h):
    def forces(xp: np.ndarray, up: np.ndarray) -> np.ndarray:
        data.displacements = up
        return _evaluate(ft, xp, areas, law, data, tangent=False).forces

    fd = nodal_differences(forces, (x, u), h)
    data.displacements = u
    return fd


# stick: small lambda, large mu; slip: large lambda, small mu
REGIMES = {"stick": (5.0, 1.0), "slip": (0.05, 1.0e4)}


@pytest.mark.parametrize("law", [LINEAR, EXPONENTIAL], ids=["linear", "exponential"])
@pytest.mark.parametrize("regime", list(REGIMES))
@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_consistent_tangent_matches_finite_differences(name, warp, regime, law):
    ft, x, u, areas, start = _springs(name, warp, 6, seed=11)
    mu, slope = REGIMES[regime]
    data = _data(u, start, mu, slope)
    ev = _evaluate(ft, x, areas, law, data)
    sliding = ev.tangential.sliding
    assert np.all(sliding) if regime == "slip" else not np.any(sliding)
    fd = _finite_difference(ft, x, u, areas, law, data, h=1e-7 * SIZE)
    error = relative_error(ev.stiffness, fd)
    assert error.max() <= 1e-6, error
    # Friction makes the element matrix unsymmetric.
    assert relative_error(ev.stiffness, ev.stiffness.transpose(0, 2, 1)).max() > 1e-6


@pytest.mark.parametrize("regime", list(REGIMES))
def test_ccx_tangent_freezes_the_projection_point(regime):
    """ccx's form drops d(phi_j)/dx u_j: equal to the exact one when the master moves rigidly."""
    ft, x, u, areas, start = _springs("quad4", 0.1, 6, seed=12)
    mu, slope = REGIMES[regime]
    u[:, :-1] = u[:, :1]  # every master node of a spring has the same displacement
    exact = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope)).stiffness
    ccx = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope, tangent_mode="ccx"))
    assert relative_error(ccx.stiffness, exact).max() <= 1e-12
    ft, x, u, areas, start = _springs("quad4", 0.1, 6, seed=12)
    exact = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope)).stiffness
    ccx = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope, tangent_mode="ccx"))
    assert relative_error(ccx.stiffness, exact).max() > 1e-6


def test_return_map_stick_and_slip_exact():
    """Stick: F_T = lambda A t_e; slip: |F_T| = mu F_N along t_e; slip update consistent."""
    ft, x, u, areas, start = _springs("quad4", 0.0, 8, seed=13)
    for regime, (mu, slope) in REGIMES.items():
        ev = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope))
        tf = ev.tangential
        n = ev.normal
        # t = t_n + s - (s.n) n
        s = tf.a - start[0]
        expected_t = start[1] + s - np.einsum("ni,ni->n", s, n)[:, None] * n
        np.testing.assert_allclose(tf.t, expected_t, rtol=0, atol=1e-14)
        if regime == "stick":
            np.testing.assert_allclose(
                tf.force, slope * areas[:, None] * (tf.t - start[2]), rtol=1e-10, atol=0
            )
            np.testing.assert_array_equal(tf.slip, start[2])
        else:
            norm = np.linalg.norm(tf.force, axis=1)
            np.testing.assert_allclose(norm, mu * ev.normal_force, rtol=1e-10)
            e = tf.elastic / np.linalg.norm(tf.elastic, axis=1)[:, None]
            np.testing.assert_allclose(tf.force / norm[:, None], e, atol=1e-12)
            # after the return, the elastic part sits exactly on the slip surface
            after = slope * areas[:, None] * (tf.t - tf.slip)
            np.testing.assert_allclose(after, tf.force, rtol=1e-10, atol=1e-12 * norm.max())
        # the slave's internal force is -F_N n + F_T; the element is self-equilibrated
        np.testing.assert_allclose(
            ev.forces[:, -1], -ev.normal_force[:, None] * n + tf.force, rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(ev.forces.sum(axis=1), 0, atol=1e-11 * np.abs(ev.forces).max())


def test_forced_stick_sticks_the_force_and_keeps_the_start_tangent():
    """ccx's elastic first iteration (docs/method.md §33.4): with ``force_stick`` the force is the
    stick one (``F_T = lambda A t_e``, slip unchanged) even where the trial force slips. The
    tangent is that force's derivative (finite differences) where the increment-start trial
    sticks; where it slips already, the friction part of the tangent is the slip one."""
    ft, x, u, areas, start = _springs("quad4", 0.1, 6, seed=14)
    mu, slope = REGIMES["slip"]
    free = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope))
    assert np.all(free.tangential.sliding)
    # the increment-start state sticks (t_n = t_p,n): the stick force and its derivative
    sticking = (start[0], start[2].copy(), start[2])
    data = _data(u, sticking, mu, slope, force_stick=True)
    ev = _evaluate(ft, x, areas, LINEAR, data)
    tf = ev.tangential
    assert not np.any(tf.sliding)
    np.testing.assert_array_equal(tf.slip, start[2])
    np.testing.assert_allclose(
        tf.force, slope * areas[:, None] * (tf.t - start[2]), rtol=1e-10, atol=0
    )
    assert np.all(np.linalg.norm(tf.force, axis=1) > 2.0 * mu * np.abs(ev.normal_force))
    fd = _finite_difference(ft, x, u, areas, LINEAR, data, h=1e-7 * SIZE)
    assert relative_error(ev.stiffness, fd).max() <= 1e-6
    # the increment-start state slips (|K_t (t_n - t_p,n)| > F_s): the force still sticks, the
    # tangent is the slip one
    forced = _evaluate(ft, x, areas, LINEAR, _data(u, start, mu, slope, force_stick=True))
    np.testing.assert_allclose(
        forced.tangential.force, slope * areas[:, None] * (forced.tangential.t - start[2]),
        rtol=1e-10, atol=0,
    )  # fmt: skip
    slip_tangent = free.tangential.dforce
    np.testing.assert_allclose(forced.tangential.dforce, slip_tangent, rtol=1e-12, atol=0)
    assert np.abs(ev.tangential.dforce - slip_tangent).max() > 1e-3 * np.abs(slip_tangent).max()


def test_friction_in_tension():
    """ccx applies mu |F_N| under linear-law tension; by choice no friction in tension."""
    weights = np.array([[-1.0, 1.0]])
    normal = np.array([[0.0, 0.0, 1.0]])
    u = np.array([[[0.0, 0.0, 0.0], [1e-3, 0.0, 0.0]]])
    zero = np.zeros((1, 3))
    base = {"mu": 0.3, "stick_slope": 1e6}
    ccx = tangential_forces(
        weights,
        normal,
        np.array([-2.0]),
        np.ones(1),
        FrictionInput(u, zero, zero, zero, **base, in_tension=True),
    )
    assert ccx.sliding[0] and np.linalg.norm(ccx.force) == pytest.approx(0.6)
    off = tangential_forces(
        weights, normal, np.array([-2.0]), np.ones(1), FrictionInput(u, zero, zero, zero, **base)
    )
    assert off.sliding[0] and np.all(off.force == 0) and off.slip[0, 0] == pytest.approx(1e-3)


def test_output_tangents():
    n = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    t1, t2 = output_tangents(n)
    np.testing.assert_allclose(t1, [[1, 0, 0], [0, 0, 1], [1, 0, 0]], atol=1e-15)
    np.testing.assert_allclose(t2, np.cross(n, t1))


def test_bad_parameters():
    weights = np.array([[-1.0, 1.0]])
    zero = np.zeros((1, 3))
    u = np.zeros((1, 2, 3))
    with pytest.raises(ValueError, match="tangent_mode"):
        tangential_forces(
            weights, zero, np.ones(1), np.ones(1),
            FrictionInput(u, zero, zero, zero, mu=0.1, stick_slope=1, tangent_mode="x"),
        )  # fmt: skip
    with pytest.raises(ValueError, match="mu"):
        tangential_forces(
            weights, zero, np.ones(1), np.ones(1),
            FrictionInput(u, zero, zero, zero, mu=np.nan, stick_slope=1),
        )  # fmt: skip


def test_friction_state_commit_and_cutback():
    from dolfinx_ntf.kernels.friction_state import FrictionState

    state = FrictionState(4)
    state.begin_increment()
    state.store(np.array([1, 2]), np.ones((2, 3)), 2 * np.ones((2, 3)), 3 * np.ones((2, 3)))
    state.commit(np.array([1, 2]))
    state.begin_increment()
    np.testing.assert_array_equal(state.start_values(np.array([2]))[2], [[3, 3, 3]])
    # a failed attempt is undone by the next begin_increment (cutback)
    state.store(np.array([2]), 9 * np.ones((1, 3)), 9 * np.ones((1, 3)), 9 * np.ones((1, 3)))
    state.begin_increment()
    np.testing.assert_array_equal(state.current["a"][2], [1, 1, 1])
    # a node that lost contact keeps its values (stale, like ccx); with reset it starts afresh
    state.commit(np.array([1]))
    assert list(state.fresh(np.array([1, 2, 3]))) == [False, True, True]
    state.anchor(np.array([2]), np.full((1, 3), 5.0))
    assert list(state.fresh(np.array([2]))) == [False]
    np.testing.assert_array_equal(state.start_values(np.array([2]))[1], [[0, 0, 0]])
    ccx = FrictionState(2, reset_on_separation=False)
    assert not ccx.fresh(np.array([0, 1])).any()
