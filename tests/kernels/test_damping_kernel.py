"""Contact damping of node-to-face springs (dolfinx_ntf.kernels.contact_damping), pure numpy.

The force ``c A P v_rel`` and its tangent through the Newmark velocity ``v = v0 + rate u``,
checked against central finite differences (docs/method.md §29).
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers.spring_differences import nodal_differences
from helpers.spring_faces import CASE_IDS, CASES, SIZE
from helpers.spring_faces import penetrating as _penetrating

from dolfinx_ntf.kernels.contact_damping import DampingInput
from dolfinx_ntf.kernels.faces import FACE_TYPES
from dolfinx_ntf.kernels.laws import LinearLaw
from dolfinx_ntf.kernels.springs import evaluate_springs

LAW = LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3)
RATE = 250.0  # dv/du, gamma/(beta dt) of a Newmark step


def _damped(ft, coords, slave, areas, v0, reference, *, coefficient, fraction, tangent):
    """The springs with velocities ``v0 + RATE (x - reference)`` at the nodes."""
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    damping = DampingInput(v0 + RATE * (nodes - reference), RATE, coefficient, fraction)
    return evaluate_springs(ft, coords, slave, areas, LAW, tangent=tangent, damping=damping)


def _finite_difference(ft, coords, slave, areas, v0, h, **kwargs):
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)

    def forces(x: np.ndarray) -> np.ndarray:
        return _damped(ft, x[:, :-1], x[:, -1], areas, v0, nodes, tangent=False, **kwargs).forces

    return nodal_differences(forces, (nodes,), h)


@pytest.mark.parametrize("fraction", [0.0, 0.4, 1.0])
@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_damping_tangent_matches_finite_differences(name, warp, fraction):
    """The tangent with damping (velocity rate, projection, normal) is the derivative."""
    ft = FACE_TYPES[name]
    coords, slave, areas, _, _ = _penetrating(ft, warp, 6, seed=11)
    rng = np.random.default_rng(5)
    v0 = rng.normal(size=(6, ft.num_nodes + 1, 3))
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    kwargs = {"coefficient": 2.0, "fraction": fraction}
    ev = _damped(ft, coords, slave, areas, v0, nodes, tangent=True, **kwargs)
    plain = evaluate_springs(ft, coords, slave, areas, LAW)
    assert np.abs(ev.forces - plain.forces).max() > 1e-2 * np.abs(plain.forces).max()
    fd = _finite_difference(ft, coords, slave, areas, v0, 1e-7 * SIZE, **kwargs)
    error = np.abs(ev.stiffness - fd).reshape(6, -1).max(axis=1)
    assert (error / np.abs(fd).reshape(6, -1).max(axis=1)).max() <= 1e-6


@pytest.mark.parametrize("name", ["tri3", "quad4", "quad8"])
def test_fallback_area_is_differentiated(name):
    """A slave node without faces (area 0: ccx's fallback ``factor |m|``): the tangent holds."""
    ft = FACE_TYPES[name]
    coords, slave, _, _, _ = _penetrating(ft, 0.1, 5, seed=12)
    areas = np.zeros(5)
    v0 = np.random.default_rng(6).normal(size=(5, ft.num_nodes + 1, 3))
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    kwargs = {"coefficient": 3.0, "fraction": 0.5}
    ev = _damped(ft, coords, slave, areas, v0, nodes, tangent=True, **kwargs)
    fd = _finite_difference(ft, coords, slave, areas, v0, 1e-7 * SIZE, **kwargs)
    # the normal force's fallback area is held constant (as ccx): compare the damping part only
    no_damping = evaluate_springs(ft, coords, slave, areas, LAW).stiffness
    fd_plain = np.zeros_like(fd)
    for node in range(ft.num_nodes + 1):
        for c in range(3):
            values = []
            for sign in (1.0, -1.0):
                x = nodes.copy()
                x[:, node, c] += sign * 1e-7 * SIZE
                ev_p = evaluate_springs(ft, x[:, :-1], x[:, -1], areas, LAW, tangent=False)
                values.append(ev_p.forces.reshape(5, -1))
            fd_plain[:, :, 3 * node + c] = (values[0] - values[1]) / (2e-7 * SIZE)
    damping_fd = fd - fd_plain
    damping_k = ev.stiffness - no_damping
    error = np.abs(damping_k - damping_fd).reshape(5, -1).max(axis=1)
    assert (error / np.abs(damping_fd).reshape(5, -1).max(axis=1)).max() <= 1e-6


def test_damping_force_is_a_dashpot_between_slave_and_face():
    """A flat quad4, the slave moving with v: F_D = c A (n.v) n + f c A (v - (n.v) n)."""
    ft = FACE_TYPES["quad4"]
    coords = np.array([[[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]]])
    slave = np.array([[0.2, -0.3, -0.01]])
    v = np.zeros((1, 5, 3))
    v[0, 4] = [0.5, -1.0, 2.0]  # slave only
    v[0, :4] = [0.1, 0.0, 0.3]  # the face translates
    damping = DampingInput(v, 0.0, 0.7, 0.25)
    ev = evaluate_springs(ft, coords, slave, np.array([1.5]), LAW, damping=damping)
    rel = v[0, 4] - v[0, 0]
    n = np.array([0.0, 0.0, 1.0])
    expected = 0.7 * 1.5 * (rel @ n * n + 0.25 * (rel - rel @ n * n))
    np.testing.assert_allclose(ev.damping.force[0], expected, rtol=1e-13)
    np.testing.assert_allclose(ev.forces.sum(axis=1), 0.0, atol=1e-13)  # self-equilibrated
    plain = evaluate_springs(ft, coords, slave, np.array([1.5]), LAW)
    np.testing.assert_allclose(ev.forces[0, 4] - plain.forces[0, 4], expected, rtol=1e-12)


def test_bad_velocities_are_named():
    ft = FACE_TYPES["quad4"]
    coords, slave, areas, _, _ = _penetrating(ft, 0.0, 2, seed=1)
    with pytest.raises(ValueError, match="velocities must have shape"):
        evaluate_springs(
            ft, coords, slave, areas, LAW, damping=DampingInput(np.zeros((2, 3)), 0, 1)
        )
    v = np.zeros((2, 5, 3))
    v[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"velocities not finite at springs \[1\]"):
        evaluate_springs(ft, coords, slave, areas, LAW, damping=DampingInput(v, 0.0, 1.0))


def test_rigid_and_2d_masters_refuse_damping():
    """Damping is built for meshed 3D masters; the others say so instead of ignoring it."""
    from dolfinx_ntf.kernels.edges import EDGE_TYPES
    from dolfinx_ntf.kernels.rigid import RigidPlane, rigid_master
    from dolfinx_ntf.kernels.segment_search import MasterCurve

    _, master = rigid_master(RigidPlane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), lambda: 1.0, "plane")
    damping = DampingInput(np.zeros((1, 2, 3)), 0.0, 1.0)
    with pytest.raises(NotImplementedError, match="plane: contact damping against a rigid"):
        master.evaluate_springs(
            None, np.zeros((1, 0, 3)), np.zeros((1, 3)), np.ones(1), LAW, damping=damping
        )
    with pytest.raises(NotImplementedError, match="not supported on 2D meshes"):
        MasterCurve.evaluate_springs(
            None, EDGE_TYPES["line2"], np.zeros((1, 2, 2)), np.zeros((1, 2)), np.ones(1), LAW,
            damping=damping,
        )  # fmt: skip
