"""Consistent nodal forces of a pressure on tri6 and quad8 faces (kernels.faces.pressure_forces)."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import QUAD8, TRI6, pressure_forces, pressure_stiffness

_ROTATION = np.linalg.qr(np.array([[1.0, 0.3, -0.2], [0.1, 1.0, 0.4], [-0.3, 0.2, 1.0]]))[0]


def _flat(face_type, scale: float) -> np.ndarray:
    """A flat face of the parametric domain scaled by ``scale``, turned and moved."""
    xi = face_type.node_parameters * scale
    x = np.column_stack([xi, np.zeros(len(xi))])
    return x @ _ROTATION.T + np.array([0.4, -1.0, 2.0])


@pytest.mark.parametrize(
    "face_type, shares",
    [(TRI6, [0, 0, 0, 1 / 3, 1 / 3, 1 / 3]), (QUAD8, [-1 / 12] * 4 + [1 / 3] * 4)],
)
def test_flat_face_gets_the_consistent_shares(face_type, shares):
    """A uniform pressure on a flat face: corners and midsides take the textbook shares of
    ``p A`` against the outward normal (tri6: 0 and 1/3; quad8: -1/12 and 1/3)."""
    x = _flat(face_type, 1.7)
    area = 1.7**2 * (0.5 if face_type is TRI6 else 4.0)
    normal = _ROTATION[:, 2]
    forces = pressure_forces(face_type, x[None], np.array([3.0]))[0]
    np.testing.assert_allclose(forces, -3.0 * area * np.outer(shares, normal), atol=1e-13)


def test_rule_and_curved_face():
    """A curved quad8 face: 2 x 2 and 3 x 3 Gauss differ, both give the same total to the
    shape's order (the total force is -p times the projected area, rule-independent for the
    component along the projection axis); a pressure on the reverse face flips the forces."""
    x = _flat(QUAD8, 1.0) @ _ROTATION  # back to the plane z = const
    x[4:, 2] += np.array([0.1, -0.05, 0.08, 0.02])  # curved edges
    g = 1 / np.sqrt(3)
    rule = (np.array([[a, b] for b in (-g, g) for a in (-g, g)]), np.ones(4))
    f3 = pressure_forces(QUAD8, x[None], np.array([2.0]))[0]
    f2 = pressure_forces(QUAD8, x[None], np.array([2.0]), rule)[0]
    assert np.abs(f3 - f2).max() > 1e-4
    # the z component of the total is -p times the area projected on z = const (exact)
    np.testing.assert_allclose(f3[:, 2].sum(), -2.0 * 4.0, rtol=1e-13)
    np.testing.assert_allclose(f2[:, 2].sum(), -2.0 * 4.0, rtol=1e-13)
    reverse = x[[0, 3, 2, 1, 7, 6, 5, 4]]
    back = pressure_forces(QUAD8, reverse[None], np.array([2.0]))[0]
    np.testing.assert_allclose(back[[0, 3, 2, 1, 7, 6, 5, 4]], -f3, atol=1e-13)


@pytest.mark.parametrize("face_type", [TRI6, QUAD8])
def test_follower_stiffness_against_central_differences(face_type):
    """``pressure_stiffness`` is the derivative of ``pressure_forces`` by the node coordinates
    (a distorted, curved face; ccx's 2 x 2 rule on the quadrilateral)."""
    rng = np.random.default_rng(7)
    n = face_type.num_nodes
    x = np.column_stack([face_type.node_parameters, np.zeros(n)]) + 0.1 * rng.normal(size=(n, 3))
    g = 1 / np.sqrt(3)
    rule = (
        None
        if face_type is TRI6
        else (np.array([[a, b] for b in (-g, g) for a in (-g, g)]), np.ones(4))
    )
    p = np.array([2.5])
    stiffness = pressure_stiffness(face_type, x[None], p, rule)[0]
    h = 1e-6
    fd = np.zeros_like(stiffness)
    for m in range(3 * n):
        d = np.zeros(3 * n)
        d[m] = h
        plus = pressure_forces(face_type, (x.ravel() + d).reshape(n, 3)[None], p, rule)
        minus = pressure_forces(face_type, (x.ravel() - d).reshape(n, 3)[None], p, rule)
        fd[:, m] = (plus - minus).ravel() / (2 * h)
    assert np.abs(stiffness - fd).max() < 1e-8 * np.abs(stiffness).max()
    assert np.abs(stiffness - stiffness.T).max() > 1e-3 * np.abs(stiffness).max()  # not symmetric
