"""The discrete spring kernels: closed forms and the tangent against finite differences."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.discrete_springs import (
    AxialSpring,
    DirectionalSpring,
    LinearSpringLaw,
    TabularSpringLaw,
)

TABLE = TabularSpringLaw(elongation=[-0.5, 0.0, 0.2, 1.0], force=[-20.0, 0.0, 3.0, 5.0])


def _finite_difference(element, reference: np.ndarray, u: np.ndarray, h: float = 1e-7):
    """Central differences of the forces with respect to the 6 dofs, shape (S, 6, 6)."""
    columns = []
    for j in range(6):
        du = np.zeros_like(u).reshape(u.shape[0], 6)
        du[:, j] = h
        du = du.reshape(u.shape)
        plus, _ = element.evaluate(reference, u + du, tangent=False)
        minus, _ = element.evaluate(reference, u - du, tangent=False)
        columns.append((plus - minus) / (2 * h))
    return np.stack(columns, axis=2)


@pytest.mark.parametrize(
    "element",
    [
        AxialSpring(LinearSpringLaw(np.array([3.0, 7.0, 1.5, 2.0, 4.0]))),
        AxialSpring(LinearSpringLaw(5.0), nlgeom=False),
        AxialSpring(TABLE),
        DirectionalSpring(TABLE, (0.0, 1.0, 0.0), (0.6, 0.0, 0.8)),
        DirectionalSpring(LinearSpringLaw(2.0), (0.0, 0.0, 1.0)),
    ],
)
def test_tangent_matches_finite_differences(element) -> None:
    rng = np.random.default_rng(3)
    reference = rng.normal(size=(5, 2, 3))
    u = 0.2 * rng.normal(size=(5, 2, 3))
    forces, tangent = element.evaluate(reference, u)
    assert forces.shape == (5, 6) and tangent.shape == (5, 6, 6)
    fd = _finite_difference(element, reference, u)
    assert np.allclose(tangent, fd, rtol=1e-6, atol=1e-6 * np.abs(tangent).max())


def test_axial_force_closed_form() -> None:
    """Stretched from length 1 to 3 along a rotated line: F = k (L - L0) along the new line."""
    reference = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]])
    u = np.array([[[0.0, 0.0, 0.0], [-1.0, 3.0, 0.0]]])  # node 2 at (0, 3, 0)
    forces, _ = AxialSpring(LinearSpringLaw(2.0)).evaluate(reference, u)
    assert np.allclose(forces[0], [0.0, -4.0, 0.0, 0.0, 4.0, 0.0])
    # without nlgeom the elongation is the displacement along the initial line: -1
    forces, _ = AxialSpring(LinearSpringLaw(2.0), nlgeom=False).evaluate(reference, u)
    assert np.allclose(forces[0], [2.0, 0.0, 0.0, -2.0, 0.0, 0.0])


def test_table_is_constant_beyond_its_ends() -> None:
    force, slope = TABLE(np.array([-2.0, 0.1, 0.6, 3.0]))
    assert np.allclose(force, [-20.0, 1.5, 4.0, 5.0])
    assert np.allclose(slope, [0.0, 15.0, 2.5, 0.0])


def test_bad_input_is_refused() -> None:
    with pytest.raises(ValueError, match="increase strictly"):
        TabularSpringLaw([0.0, 0.0], [1.0, 2.0])
    with pytest.raises(ValueError, match="unit 3-vector"):
        DirectionalSpring(LinearSpringLaw(1.0), (1.0, 1.0, 0.0))
    with pytest.raises(ValueError, match="coincident"):
        AxialSpring(LinearSpringLaw(1.0)).evaluate(np.zeros((1, 2, 3)), np.zeros((1, 2, 3)))
