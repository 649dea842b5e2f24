"""C3D20's space as a constrained Q2 space (dolfinx_ntf.fem.serendipity, docs/method.md §13.5)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

import basix
import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import num_equations
from dolfinx_ntf.fem.serendipity import serendipity_constraints

pytestmark = pytest.mark.serial


def _classical_c3d20(xi: np.ndarray) -> np.ndarray:
    """The 20 serendipity shape functions on [-1, 1]^3 (corners, then edge midpoints)."""
    corners = np.array([[a, b, c] for c in (-1, 1) for b in (-1, 1) for a in (-1, 1)], float)
    edges = [(0, 1), (0, 2), (0, 4), (1, 3), (1, 5), (2, 3), (2, 6), (3, 7), (4, 5), (4, 6),
             (5, 7), (6, 7)]  # fmt: skip
    mids = np.array([(corners[a] + corners[b]) / 2 for a, b in edges])
    x, y, z = xi.T
    columns = []
    for cx, cy, cz in corners:
        columns.append(
            (1 + x * cx) * (1 + y * cy) * (1 + z * cz) * (x * cx + y * cy + z * cz - 2) / 8
        )
    for m in mids:
        factors = [(1 - v**2) if c == 0 else (1 + v * c) for v, c in zip((x, y, z), m)]
        columns.append(factors[0] * factors[1] * factors[2] / 4)
    return np.column_stack(columns)


def test_basix_serendipity_space_is_the_classical_20_node_space():
    element = basix.create_element(
        basix.ElementFamily.serendipity,
        basix.CellType.hexahedron,
        2,
        basix.LagrangeVariant.legendre,
        basix.DPCVariant.legendre,
    )
    points = np.random.default_rng(0).uniform(0, 1, (200, 3))
    basis = element.tabulate(0, points)[0, :, :, 0]  # (points, 20)
    classical = _classical_c3d20(2 * points - 1)
    coefficients, *_ = np.linalg.lstsq(basis, classical, rcond=None)
    assert np.abs(basis @ coefficients - classical).max() < 1e-12
    assert np.linalg.matrix_rank(coefficients) == 20  # the same 20-dimensional space
    # and the constrained Q2 weights are the classical functions at face and cell centres
    at = _classical_c3d20(np.array([[1.0, 0, 0], [0, 0, 0]]))
    assert sorted(set(np.round(at[0], 12))) == [-0.25, 0.0, 0.5]
    assert sorted(set(np.round(at[1], 12))) == [-0.25, 0.25]


def _solve(mesh, V, constraints=None):
    """Linear elasticity, clamped bottom, body force; ``constraints`` None: a plain linear solve."""
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)

    def sigma(w):
        eps = ufl.sym(ufl.grad(w))
        return 2.0 * eps + 1.0 * ufl.tr(eps) * ufl.Identity(3)

    x = ufl.SpatialCoordinate(mesh)
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 5})  # 3x3x3 Gauss
    load = ufl.inner(ufl.as_vector((x[1], 0.0, -x[0])), v) * dx
    bottom = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda p: np.isclose(p[2], 0.0))
    dofs = dolfinx.fem.locate_dofs_topological(V, 2, bottom)
    if constraints:  # face-centre dofs follow from the nodes
        dependent = set(np.concatenate([c.nodes[:, 0] for c in constraints]).tolist())
        dofs = np.array([d for d in dofs if int(d) not in dependent], dtype=np.int32)
    bc = dolfinx.fem.dirichletbc(dolfinx.fem.Function(V), dofs)
    if constraints is None:
        problem = compat.linear_problem(
            ufl.inner(sigma(ufl.TrialFunction(V)), ufl.grad(v)) * dx,
            load,
            bcs=[bc],
            petsc_options={"ksp_type": "preonly", "pc_type": "lu"},
        )
        return problem.solve()
    F = ufl.inner(sigma(u), ufl.grad(v)) * dx - load
    problem = ntf.ContactProblem(F, u, [], [bc], constraints=constraints)
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    solver.solve(u)
    return u


def test_constrained_q2_solves_like_the_serendipity_element():
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], dolfinx.mesh.CellType.hexahedron
    )
    mesh.geometry.x[:, 0] += 0.1 * mesh.geometry.x[:, 1] * mesh.geometry.x[:, 2]  # distorted
    S = compat.vector_space(mesh, "S", 2)
    Q = compat.vector_space(mesh, "Lagrange", 2)
    constraints = serendipity_constraints(Q)
    assert num_equations(constraints) == 3 * (36 + 8)  # 36 faces, 8 cells, 3 components
    u_s = _solve(mesh, S)
    u_q = _solve(mesh, Q, constraints)
    P1 = compat.vector_space(mesh, "Lagrange", 1)
    w_s, w_q = dolfinx.fem.Function(P1), dolfinx.fem.Function(P1)
    w_s.interpolate(u_s)
    w_q.interpolate(u_q)
    scale = np.abs(w_s.x.array).max()
    assert scale > 1e-2
    assert np.abs(w_s.x.array - w_q.x.array).max() < 1e-10 * scale
    # and it is not the plain Q2 solution
    u_plain = _solve(mesh, Q)
    w_p = dolfinx.fem.Function(P1)
    w_p.interpolate(u_plain)
    assert np.abs(w_p.x.array - w_s.x.array).max() > 1e-4 * scale


def test_constraint_blocks_eliminate_like_single_constraints():
    """The vectorized blocks give the rows of one LinearConstraint per row."""
    from dolfinx_ntf.fem.constraints import LinearConstraintBlock, elimination_rows

    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 1, 1], dolfinx.mesh.CellType.hexahedron
    )
    Q = compat.vector_space(mesh, "Lagrange", 2)
    blocks = serendipity_constraints(Q)
    assert all(isinstance(b, LinearConstraintBlock) for b in blocks)
    singles = [
        ntf.LinearConstraint(b.nodes[k], b.components[k], b.coefficients[k])
        for b in blocks
        for k in range(len(b))
    ]
    n = 3 * compat.cell_dofs(Q).max() + 3
    s_block, M_block, g_block = elimination_rows(n, blocks)
    s_single, M_single, g_single = elimination_rows(n, singles)
    np.testing.assert_array_equal(s_block, s_single)
    assert abs(M_block - M_single).max() == 0.0
    assert np.all(g_block == 0.0) and np.all(g_single == 0.0)
    # every face centre once (11 faces of two cells), then the 2 cell centres
    assert [len(b) for b in blocks] == [3 * 11, 3 * 2]


def test_constraint_block_checks_its_arrays():
    from dolfinx_ntf.fem.constraints import LinearConstraintBlock

    with pytest.raises(ValueError, match=r"'bad'.*do not match"):
        LinearConstraintBlock(np.zeros((2, 3)), 0, np.ones(4), name="bad")
    with pytest.raises(ValueError, match="components must be 0, 1 or 2"):
        LinearConstraintBlock(np.zeros((2, 3)), 3, np.ones(3))
    with pytest.raises(ValueError, match="not a mesh node"):
        LinearConstraintBlock(-np.ones((2, 3)), 0, np.ones(3))


def test_quad9_faces_with_serendipity_centres_become_quad8():
    from dolfinx_ntf.fem.serendipity import as_quad8, face_centres
    from dolfinx_ntf.fem.surfaces import boundary_faces

    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 1], dolfinx.mesh.CellType.hexahedron
    )
    Q = compat.vector_space(mesh, "Lagrange", 2)
    mesh.topology.create_connectivity(2, 3)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda p: np.isclose(p[2], 1.0))
    faces = boundary_faces(Q, top)
    assert faces.face_type.name == "quad9"
    centres = face_centres(serendipity_constraints(Q))
    quad8 = as_quad8(faces, centres)
    assert quad8.face_type.name == "quad8"
    np.testing.assert_array_equal(quad8.faces, faces.faces[:, :8])
    assert not np.isin(quad8.faces, centres).any()
    assert as_quad8(faces, np.zeros(0, np.int64)) is faces  # plain Q2: unchanged
    with pytest.raises(ValueError, match="mixes serendipity"):
        as_quad8(faces, centres[~np.isin(centres, faces.faces[:1, 8])])


@pytest.mark.mpi
def test_trilinear_midsides_solve_like_q1():
    """Q2 with the serendipity and midside constraints on every cell is the Q1 space (C3D8)."""
    from dolfinx_ntf.fem.serendipity import trilinear_constraints

    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [2, 2, 2], dolfinx.mesh.CellType.hexahedron
    )
    mesh.geometry.x[:, 0] += 0.1 * mesh.geometry.x[:, 1] * mesh.geometry.x[:, 2]  # distorted
    Q = compat.vector_space(mesh, "Lagrange", 2)
    num_cells = mesh.topology.index_map(3).size_local + mesh.topology.index_map(3).num_ghosts
    edges = trilinear_constraints(Q, np.arange(num_cells))
    u_q = _solve(mesh, Q, [*serendipity_constraints(Q), edges])
    u_1 = _solve(mesh, compat.vector_space(mesh, "Lagrange", 1))
    w_q = dolfinx.fem.Function(u_1.function_space)
    w_q.interpolate(u_q)
    scale = np.abs(u_1.x.array).max()
    assert scale > 1e-2
    assert np.abs(w_q.x.array - u_1.x.array).max() < 1e-10 * scale
    w_s = dolfinx.fem.Function(u_1.function_space)  # the serendipity space alone is not Q1
    w_s.interpolate(_solve(mesh, Q, serendipity_constraints(Q)))
    assert np.abs(w_s.x.array - u_1.x.array).max() > 1e-4 * scale
    # the midside values are the means of their edges' ends
    values = u_q.x.array.reshape(-1, 3)
    np.testing.assert_allclose(
        values[edges.nodes[:, 0]], 0.5 * (values[edges.nodes[:, 1]] + values[edges.nodes[:, 2]]),
        atol=1e-12 * scale,
    )  # fmt: skip
    # faces of these cells are quad4 faces of their corners
    from dolfinx_ntf.fem.serendipity import as_quad8, face_centres, linear_midsides
    from dolfinx_ntf.fem.surfaces import boundary_faces

    mesh.topology.create_connectivity(2, 3)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda p: np.isclose(p[2], 1.0))
    faces = boundary_faces(Q, top)
    centres = face_centres(serendipity_constraints(Q))
    midsides = linear_midsides([edges])
    if faces.faces.shape[0]:
        quad4 = as_quad8(faces, centres, midsides)
        assert quad4.face_type.name == "quad4"
        np.testing.assert_array_equal(quad4.faces, faces.faces[:, :4])
        assert as_quad8(faces, centres).face_type.name == "quad8"  # without the midsides
