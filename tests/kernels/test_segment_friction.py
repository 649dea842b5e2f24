"""Friction of the 2D node-to-segment springs (kernels.segment_springs with a FrictionInput)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.spring_differences import nodal_differences, relative_error

from dolfinx_ntf.kernels.edges import EDGE_TYPES, EdgeType
from dolfinx_ntf.kernels.friction import FrictionInput
from dolfinx_ntf.kernels.laws import ExponentialLaw, LinearLaw, TabularLaw
from dolfinx_ntf.kernels.segment_springs import evaluate_segment_springs

LAWS = {
    "linear": LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3),
    "exponential": ExponentialLaw(c0=0.2, p0=3.0),
    "tabular": TabularLaw([0.0, 50.0, 400.0], [0.0, 0.05, 0.2]),
    "hard": LinearLaw(slope=1.0e6, tension=1.0),
}
# stick: a soft tangential spring and a large mu; slip: a stiff one and a small mu
REGIMES = {"stick": (5.0, 1.0), "slip": (0.05, 1.0e4)}


def _springs(edge_type: EdgeType, num: int, seed: int, depth: tuple[float, float]):
    """Current nodes x (N, n+1, 2) of penetrating springs, displacements u and a start state."""
    rng = np.random.default_rng(seed)
    n = edge_type.num_nodes
    master = np.zeros((num, n, 2))
    master[:, 0, 0], master[:, 1, 0] = -1.0, 1.0
    master[:, :2] += 0.05 * rng.uniform(-1, 1, (num, 2, 2))
    if n == 3:
        master[:, 2] = 0.5 * (master[:, 0] + master[:, 1]) + [0.0, 0.2]
    angle = rng.uniform(0, 2 * np.pi, num)
    c, s = np.cos(angle), np.sin(angle)
    rot = np.stack([np.stack([c, -s], axis=1), np.stack([s, c], axis=1)], axis=1)
    master = np.einsum("nij,nkj->nki", rot, master) + rng.uniform(-5, 5, (num, 1, 2))
    xi = rng.uniform(-0.7, 0.7, (num, 1))
    q = np.einsum("nj,njc->nc", edge_type.shape_functions(xi), master)
    t = np.einsum("nj,njc->nc", edge_type.shape_derivatives(xi), master)
    normal = np.stack([t[:, 1], -t[:, 0]], axis=1) / np.linalg.norm(t, axis=1)[:, None]
    slave = q - rng.uniform(*depth, num)[:, None] * normal
    x = np.concatenate([master, slave[:, None]], axis=1)
    u = 0.1 * rng.uniform(-1, 1, x.shape)
    # t_n and t_p,n of an earlier increment on this edge lie along its tangent (to first order)
    tangent = t / np.linalg.norm(t, axis=1)[:, None]
    a_start = 0.1 * rng.uniform(-1, 1, (num, 2))
    t_start, slip_start = (0.02 * rng.uniform(-1, 1, (num, 1)) * tangent for _ in range(2))
    return x, u, rng.uniform(0.5, 2.0, num), (a_start, t_start, slip_start)


def _evaluate(edge_type, x, areas, law, data, **options):
    return evaluate_segment_springs(
        edge_type, x[:, :-1], x[:, -1], areas, law, friction=data, **options
    )


def _finite_difference(edge_type, x, u, areas, law, data, h):
    """Central differences of the forces by the nodal positions (u moves with x)."""

    def forces(xp: np.ndarray, up: np.ndarray) -> np.ndarray:
        data.displacements = up
        return _evaluate(edge_type, xp, areas, law, data, tangent=False).forces

    fd = nodal_differences(forces, (x, u), h)
    data.displacements = u
    return fd


def _fd_frictionless(edge_type, x, areas, law, h):
    """Central differences of the frictionless forces (same steps as ``_finite_difference``)."""

    def forces(xp: np.ndarray) -> np.ndarray:
        return evaluate_segment_springs(
            edge_type, xp[:, :-1], xp[:, -1], areas, law, tangent=False
        ).forces

    return nodal_differences(forces, (x,), h)


@pytest.mark.parametrize("law_name", sorted(LAWS))
@pytest.mark.parametrize("regime", sorted(REGIMES))
@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_frictional_tangent_matches_finite_differences(edge_name, regime, law_name):
    """The exact tangent with friction equals central differences, in stick and in slip."""
    edge_type, law = EDGE_TYPES[edge_name], LAWS[law_name]
    depth = (1e-5, 1e-4) if law_name == "hard" else (0.005, 0.04)
    x, u, areas, start = _springs(edge_type, 8, seed=21, depth=depth)
    mu, slope = REGIMES[regime]
    data = FrictionInput(u, *start, mu=mu, stick_slope=slope)
    ev = _evaluate(edge_type, x, areas, law, data)
    assert np.all(ev.normal_force > 0)
    sliding = ev.tangential.sliding
    assert np.all(sliding) if regime == "slip" else not np.any(sliding)
    fd = _finite_difference(edge_type, x, u, areas, law, data, h=1e-7)
    assert relative_error(ev.stiffness, fd).max() <= 1e-6
    # the friction part alone (the normal spring's tangent taken out of both) matches too
    plain = evaluate_segment_springs(edge_type, x[:, :-1], x[:, -1], areas, law).stiffness
    fd_plain = _fd_frictionless(edge_type, x, areas, law, h=1e-7)
    assert relative_error(ev.stiffness - plain, fd - fd_plain).max() <= 1e-6
    # friction makes the element matrix unsymmetric (no symmetrization even when asked for)
    sym = _evaluate(edge_type, x, areas, law, data, symmetric=True).stiffness
    assert relative_error(sym, sym.transpose(0, 2, 1)).max() > 1e-9  # round-off: 1e-16


@pytest.mark.parametrize("regime", sorted(REGIMES))
@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_ccx_tangent_freezes_the_projection_point(edge_name, regime):
    """ccx's form drops dφ_j/dx u_j: equal to the exact one when the master moves rigidly.

    In slip the two agree for any motion in 2D: the slip direction is ±the edge tangent, and
    (I - e e) removes the tangential ``ds`` term in which they differ.
    """
    edge_type = EDGE_TYPES[edge_name]
    x, u, areas, start = _springs(edge_type, 6, seed=22, depth=(0.005, 0.04))
    mu, slope = REGIMES[regime]
    rigid = u.copy()
    rigid[:, :-1] = rigid[:, :1]
    for displacements, equal in ((rigid, True), (u, regime == "slip")):
        law = LAWS["linear"]
        exact = _evaluate(edge_type, x, areas, law, FrictionInput(displacements, *start, mu, slope))
        ccx_data = FrictionInput(displacements, *start, mu, slope, tangent_mode="ccx")
        ccx = _evaluate(edge_type, x, areas, law, ccx_data)
        error = relative_error(ccx.stiffness, exact.stiffness).max()
        assert error <= 1e-12 if equal else error > 1e-6


@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_return_map_along_the_edge(edge_name):
    """F_T lies along the edge; stick: F_T = λ A t_e; slip: |F_T| = μ F_N; equilibrium."""
    edge_type = EDGE_TYPES[edge_name]
    x, u, areas, start = _springs(edge_type, 10, seed=23, depth=(0.005, 0.04))
    law = LAWS["linear"]
    for regime, (mu, slope) in REGIMES.items():
        ev = _evaluate(edge_type, x, areas, law, FrictionInput(u, *start, mu, slope))
        tf, n = ev.tangential, ev.normal
        assert tf.force.shape == (10, 2) and tf.t.shape == (10, 2)
        s = tf.a - start[0]
        expected_t = start[1] + s - np.einsum("ni,ni->n", s, n)[:, None] * n
        np.testing.assert_allclose(tf.t, expected_t, rtol=0, atol=1e-14)
        # one tangent direction: with t_n along the edge, the tangential force is normal to n
        along_n = np.einsum("ni,ni->n", tf.force, n)
        assert np.max(np.abs(along_n)) <= 1e-12 * np.abs(tf.force).max()
        if regime == "stick":
            np.testing.assert_allclose(tf.force, slope * areas[:, None] * (tf.t - start[2]))
            np.testing.assert_array_equal(tf.slip, start[2])
        else:
            norm = np.linalg.norm(tf.force, axis=1)
            np.testing.assert_allclose(norm, mu * ev.normal_force, rtol=1e-12)
            after = slope * areas[:, None] * (tf.t - tf.slip)  # back on the slip surface
            np.testing.assert_allclose(after, tf.force, rtol=1e-10, atol=1e-12 * norm.max())
        np.testing.assert_allclose(
            ev.forces[:, -1], -ev.normal_force[:, None] * n + tf.force, rtol=1e-12, atol=1e-12
        )
        np.testing.assert_allclose(ev.forces.sum(axis=1), 0, atol=1e-11 * np.abs(ev.forces).max())


def test_three_component_state_is_read_in_the_plane():
    """The pairing's padded 3-vectors (z = 0) give the same answer as 2-vectors."""
    edge_type = EDGE_TYPES["line2"]
    x, u, areas, start = _springs(edge_type, 5, seed=24, depth=(0.005, 0.04))
    plane = _evaluate(edge_type, x, areas, LAWS["linear"], FrictionInput(u, *start, 0.05, 1e4))
    padded = FrictionInput(
        np.concatenate([u, np.zeros((*u.shape[:2], 1))], axis=2),
        *(np.hstack([v, np.zeros((5, 1))]) for v in start),
        0.05,
        1e4,
    )
    x3 = np.concatenate([x, np.zeros((*x.shape[:2], 1))], axis=2)
    spatial = _evaluate(edge_type, x3, areas, LAWS["linear"], padded)
    np.testing.assert_array_equal(plane.forces, spatial.forces)
    np.testing.assert_array_equal(plane.stiffness, spatial.stiffness)


def test_bad_friction_input_names_the_array():
    """A state of the wrong shape is a ValueError naming it, not a broadcasting error."""
    edge_type = EDGE_TYPES["line2"]
    x, u, areas, start = _springs(edge_type, 4, seed=25, depth=(0.005, 0.04))
    bad = FrictionInput(u, start[0][:3], start[1], start[2], 0.3, 1e3)
    with pytest.raises(ValueError, match="a_start"):
        _evaluate(edge_type, x, areas, LAWS["linear"], bad)


@pytest.mark.parametrize("regime", sorted(REGIMES))
@pytest.mark.parametrize("edge_name", sorted(EDGE_TYPES))
def test_frictional_tangent_at_clamped_projections(edge_name, regime):
    """Slave nodes beside the edge ends (ξ fixed at ±1): the exact tangent still matches."""
    edge_type = EDGE_TYPES[edge_name]
    x, u, areas, start = _springs(edge_type, 8, seed=26, depth=(0.005, 0.04))
    end = np.where(np.arange(8) % 2, 1.0, -1.0)[:, None]
    t_end = np.einsum("nj,njc->nc", edge_type.shape_derivatives(end), x[:, :-1])
    q_end = np.einsum("nj,njc->nc", edge_type.shape_functions(end), x[:, :-1])
    normal = np.stack([t_end[:, 1], -t_end[:, 0]], axis=1) / np.linalg.norm(t_end, axis=1)[:, None]
    x[:, -1] = q_end - 0.02 * normal + 0.05 * end * t_end / np.linalg.norm(t_end, axis=1)[:, None]
    mu, slope = REGIMES[regime]
    data = FrictionInput(u, *start, mu=mu, stick_slope=slope)
    ev = _evaluate(edge_type, x, areas, LAWS["linear"], data)
    np.testing.assert_array_equal(ev.xi, end)
    sliding = ev.tangential.sliding
    assert np.all(sliding) if regime == "slip" else not np.any(sliding)
    fd = _finite_difference(edge_type, x, u, areas, LAWS["linear"], data, h=1e-7)
    assert relative_error(ev.stiffness, fd).max() <= 1e-6
