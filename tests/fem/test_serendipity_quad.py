"""The 8-node serendipity quadrilateral as a constrained Q2 space (fem/serendipity_quad.py)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.serendipity_quad import (
    CENTRE_WEIGHTS,
    add_quad_centres,
    has_quad_centres,
    quad_forces_on_nodes,
    quad_serendipity_constraints,
)

pytestmark = pytest.mark.serial


def _quad8_mesh():
    """Two 8-node quadrilaterals (one curved edge) with their centres added, dolfinx order."""
    x = np.array(
        [[0, 0], [1, 0], [0, 1], [1, 1], [2, 0], [2, 1.2],  # vertices
         [0.5, -0.1], [0, 0.5], [1, 0.5], [0.5, 1], [1.5, 0], [2.05, 0.6], [1.5, 1.1]],
        dtype=float,
    )  # fmt: skip
    cells = np.array([[0, 1, 2, 3, 6, 7, 8, 9], [1, 4, 3, 5, 10, 8, 11, 12]])
    return add_quad_centres(cells, x)


def test_centres_are_the_serendipity_values():
    """A quadratic field of the 8 nodes (serendipity reproduces it) takes its centre value."""
    cells, x = _quad8_mesh()
    assert cells.shape == (2, 9) and x.shape == (15, 2)
    # the centre of each cell is -1/4 corners + 1/2 midsides of its 8 nodes
    for c in range(2):
        np.testing.assert_allclose(x[cells[c, 8]], CENTRE_WEIGHTS @ x[cells[c, :8]], atol=1e-15)
    np.testing.assert_allclose(CENTRE_WEIGHTS.sum(), 1.0)  # constants reproduced


def test_constraints_fix_the_centre_and_forces_keep_their_sum():
    cells, x = _quad8_mesh()
    domain = compat.coordinate_element("quadrilateral", 2, 2)
    mesh = compat.create_mesh(MPI.COMM_SELF, cells, x, domain)
    V = compat.vector_space(mesh, "Lagrange", 2)
    (block,) = quad_serendipity_constraints(V)
    assert block.block_size == 2 and block.nodes.shape == (4, 9)  # 2 cells x 2 components
    assert has_quad_centres([block]) and not has_quad_centres([])
    # the rows see a field that is not in the quad8 space; a linear field (in it) satisfies them
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda p: np.vstack([p[0] ** 2 + p[1], p[0] * p[1]]))
    values = u.x.array[block.dofs]
    residual = np.einsum("km,km->k", values, np.broadcast_to(block.coefficients, values.shape))
    assert np.abs(residual).max() > 1e-6
    u.interpolate(lambda p: np.vstack([2 * p[0] - p[1] + 1, 0.5 * p[1]]))
    values = u.x.array[block.dofs]
    residual = np.einsum("km,km->k", values, np.broadcast_to(block.coefficients, values.shape))
    np.testing.assert_allclose(residual, 0.0, atol=1e-12)  # linear fields are in the space
    # element forces: the centre's moves to the 8 nodes, the sum per cell is kept
    W = compat.vector_space(mesh, "DQ", 2)
    forces = np.random.default_rng(1).normal(size=W.dofmap.index_map.size_local * 2)
    on_nodes = quad_forces_on_nodes(forces, W).reshape(2, 8, 2)
    per_cell = forces.reshape(-1, 2)[compat.cell_dofs(W)]
    np.testing.assert_allclose(on_nodes.sum(axis=1), per_cell.sum(axis=1), atol=1e-12)
