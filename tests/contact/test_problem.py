"""Full contact solves on two-block meshes: assembly, equilibrium, patch test, Newton convergence,
bad input."""

import itertools

import numpy as np
import pytest
import scipy.sparse
from helpers import (
    LOWER_TOP,
    UPPER,
    UPPER_BOTTOM,
    elastic_residual,
    punch_problem,
    solve_increments,
    two_blocks,
)
from helpers.jacobian_check import directional_derivative

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial

E, NU = 1000.0, 0.3


_elastic_residual = elastic_residual
_setup = punch_problem


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_equilibrium_contact_force_equals_load(cell):
    problem, pressure, _ = _setup(cell)
    load = 10.0
    solve_increments(problem, pressure, load)
    res = ntf.contact_results(problem)[0]
    punch_area = 0.6 * 0.6
    vertical = res.force[:, 2].sum()  # force of the master on the slave nodes
    assert vertical == pytest.approx(load * punch_area, rel=1e-10)
    # Σ p·A over the slave nodes carries the load (normals are vertical up to the master's small
    # rotation).
    assert np.sum(res.pressure * res.area) == pytest.approx(load * punch_area, rel=1e-4)
    assert np.all(res.clearance < 0)


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_patch_test_uniform_pressure(cell):
    full = ((0.0, 0.0, 0.0), (1.0, 1.0, 0.5), (4, 4, 2))
    problem, pressure, _ = _setup(cell, upper=full, rollers=True)
    solve_increments(problem, pressure, load=10.0)
    res = ntf.contact_results(problem)[0]
    assert res.node.size == 25
    # Uniform to 1e-8; its value is the load over the *current* area (spring areas follow the
    # deformation).
    np.testing.assert_allclose(res.pressure, res.pressure.mean(), rtol=1e-8)
    assert np.sum(res.pressure * res.area) == pytest.approx(10.0, rel=1e-10)
    assert res.pressure.mean() == pytest.approx(10.0, rel=1e-2)


def test_newton_converges_quadratically():
    problem, pressure, _ = _setup("hexahedron")
    solver, _ = solve_increments(problem, pressure, increments=1)
    r = np.array(solver.residual_norms) / solver.residual_norms[0]
    above_roundoff = r[r > 1e-12]
    assert len(above_roundoff) >= 3
    for before, after in itertools.pairwise(above_roundoff):
        assert after <= 100 * before**2, f"residual ratios {r}"


def test_assembled_contact_matrix_matches_element_matrices():
    problem, pressure, _ = _setup("hexahedron")
    solve_increments(problem, pressure, increments=1)
    x = compat.petsc_vector(problem.u)
    problem.form(x)
    A_full = problem.ensure_matrix()
    problem.J(x, A_full)
    A_bulk = dolfinx.fem.petsc.assemble_matrix(problem.a, problem.bcs)
    A_bulk.assemble()

    def to_scipy(A):
        indptr, indices, data = A.getValuesCSR()
        return scipy.sparse.csr_matrix((data, indices, indptr), shape=A.getSize())

    contact = to_scipy(A_full) - to_scipy(A_bulk)
    rng = np.random.default_rng(0)
    w = rng.standard_normal(contact.shape[1])
    bc_dofs = np.concatenate([bc.dof_indices()[0] for bc in problem.bcs])
    w[bc_dofs] = 0.0
    expected = np.zeros_like(w)
    for state in problem.states:
        nodes = state.element_nodes
        dofs = (3 * nodes[:, :, None] + np.arange(3)).reshape(nodes.shape[0], -1)
        np.add.at(expected, dofs, np.einsum("eij,ej->ei", state.evaluation.stiffness, w[dofs]))
    expected[bc_dofs] = 0.0
    np.testing.assert_allclose(contact @ w, expected, atol=1e-9 * np.abs(expected).max())
    assert np.abs(expected).max() > 0


def test_options_symmetric_and_linearized_area_converge():
    for options in ({"symmetric": True}, {"linearize_area": True}):
        problem, pressure, _ = _setup("hexahedron", **options)
        solve_increments(problem, pressure)
        res = ntf.contact_results(problem)[0]
        assert res.force[:, 2].sum() == pytest.approx(3.6, rel=1e-10)


def test_exponential_law_solve():
    problem, pressure, _ = _setup("hexahedron", law=ntf.ExponentialLaw(c0=1e-3, p0=1.0))
    solve_increments(problem, pressure)
    res = ntf.contact_results(problem)[0]
    assert res.force[:, 2].sum() == pytest.approx(3.6, rel=1e-10)


def test_newton_failure_raises():
    problem, pressure, _ = _setup("hexahedron")
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem, max_it=1)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", 10 * t), fixed=True)
    with pytest.raises(
        ntf.ContactConvergenceError,
        match=r"failed after 1 attempt\(s\) \(fixed increments\): Newton did not converge",
    ):
        step.run(solver, problem.u)


def test_bad_inputs_give_clear_errors():
    mesh, _, ft = two_blocks()
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = _elastic_residual(u, v, ft, 0.0)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E))
    slave, master = ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP)
    with pytest.raises(ValueError, match=r"facet tag value\(s\) \[99\] not found"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, ntf.FacetSurface(ft, 99), law)])
    with pytest.raises(ValueError, match="both the slave and the master"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(master, master, law)])
    with pytest.raises(ValueError, match="must be a FacetSurface"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, ntf.NodeSurface(np.array([0])), law)])
    with pytest.raises(ValueError, match=r"outside 0\.\."):
        ntf.ContactProblem(F, u, [ntf.ContactPair(ntf.NodeSurface(np.array([10**7])), master, law)])
    with pytest.raises(ValueError, match="friction_tangent"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, master, law)], friction_tangent="exact")
    with pytest.raises(ValueError, match="overlap_ramp"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, master, law)], overlap_ramp="step")
    cell_tags = dolfinx.mesh.meshtags(
        mesh, 3, np.array([0], dtype=np.int32), np.array([1], dtype=np.int32)
    )
    with pytest.raises(ValueError, match="facet tags"):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, ntf.FacetSurface(cell_tags, 1), law)])
    W = compat.scalar_space(mesh, "Lagrange", 1)
    w = dolfinx.fem.Function(W)
    with pytest.raises(ValueError, match="vector displacement"):
        ntf.ContactProblem(
            ufl.inner(ufl.grad(w), ufl.grad(ufl.TestFunction(W))) * ufl.dx,
            w,
            [ntf.ContactPair(slave, master, law)],
        )
    with pytest.raises(ValueError, match="min_increment"):
        problem = ntf.ContactProblem(F, u, [ntf.ContactPair(slave, master, law)])
        ntf.StaticStep(lambda t: None, initial_increment=2.0, max_increment=1.0).run(
            ntf.ContactNewtonSolver(mesh.comm, problem), u
        )


def test_node_based_slave_collects_lateral_area():
    mesh, ct, ft = two_blocks(upper=((0.25, 0.25, 0.0), (0.5, 0.5, 0.5), (2, 2, 2)))
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = _elastic_residual(u, v, ft, 0.0)
    upper_vertices = compat.incident_entities(mesh, ct.find(UPPER), 3, 0)
    bottom_vertices = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[2], 0.0))
    vertices = np.intersect1d(upper_vertices, bottom_vertices)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E))
    nodal = ntf.ContactProblem(
        F, u, [ntf.ContactPair(ntf.NodeSurface(vertices), ntf.FacetSurface(ft, LOWER_TOP), law)]
    )
    faces = nodal.states[0].slave.faces.faces
    # bottom faces (4) plus lateral faces touching the bottom rim (2 per side)
    assert faces.shape[0] == 4 + 8
    nodal.begin_increment(1.0)
    from dolfinx_ntf.kernels.spring_areas import spring_areas

    coords = nodal.current_coordinates()
    areas = spring_areas(
        nodal.states[0].slave.faces.face_type, faces, coords, nodal.states[0].slave.nodes
    )
    # corner node: a quarter of one bottom face and of two lateral faces
    assert np.isclose(areas.max(), 0.25 * 0.0625 * 4)  # centre node: four bottom quarter faces
    assert np.isclose(np.sort(areas)[0], 0.25 * (0.0625 + 2 * 0.0625))


def test_walk_from_previous_face_stops_edge_ping_pong():
    """Tets: slave nodes on shared master edges flip faces at each re-pairing (ccx behaviour) until
    iteration 9; starting the walk at the previous face keeps them put, and Newton converges as on
    hexahedra."""
    iterations = {}
    for option in (False, True):
        problem, pressure, _ = _setup("tetrahedron", walk_from_previous_face=option)
        _, results = solve_increments(problem, pressure)
        iterations[option] = [r.iterations for r in results]
        assert ntf.contact_results(problem)[0].force[:, 2].sum() == pytest.approx(3.6, rel=1e-10)
    assert max(iterations[True]) <= 5
    assert max(iterations[False]) > max(iterations[True])


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
@pytest.mark.parametrize("linearize_area", [False, True])
def test_global_jacobian_matches_finite_differences(cell, linearize_area):
    """The assembled Jacobian is the exact derivative of the assembled residual for a fixed pairing:
    areas held at their pairing values (ccx), or recomputed and linearized (linearize_area)."""
    problem, pressure, _ = _setup(cell, linearize_area=linearize_area)
    solve_increments(problem, pressure, increments=1)
    check = directional_derivative(problem, amplitude=1e-3, h=1e-4, seed=1)
    np.testing.assert_allclose(check.product, check.difference, atol=1e-6 * check.contact_scale)


def test_body_without_springs_fails_with_a_hint():
    """A punch above the block (open gap, no springs) under a load has no support: a clear error
    at the first iteration (the Jacobian is singular), no NaN."""
    problem, pressure, _ = _setup(gap=0.05)
    u = problem.u
    solver = ntf.ContactNewtonSolver(u.function_space.mesh.comm, problem, max_it=8)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", 10 * t), min_increment=0.5)
    with pytest.raises(ntf.ContactSolverError, match=r"singular.*no contact springs"):
        step.run(solver, u)
    assert np.all(np.isfinite(u.x.array))


def test_initial_overlap_is_ramped_in_the_first_increment_only():
    """docs/method.md §3.5: in increment 1 of step 1 only the fraction tau of an initial overlap is
    active; g0 is reset at every later increment start, so from increment 2 on the whole overlap
    acts."""
    overlap = 0.01
    mesh, _, ft = two_blocks(upper=((0.2, 0.2, 0.0), (0.6, 0.6, 0.5), (3, 3, 2)), gap=-overlap)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E)),
    )
    problem = ntf.ContactProblem(_elastic_residual(u, v, ft, 0.0), u, [pair])
    problem.begin_increment(0.25)
    problem.evaluate(tangent=False)
    np.testing.assert_allclose(
        ntf.contact_results(problem)[0].clearance, -0.25 * overlap, rtol=1e-12
    )
    problem.begin_increment(0.5)
    problem.evaluate(tangent=False)
    np.testing.assert_allclose(ntf.contact_results(problem)[0].clearance, -overlap, rtol=1e-12)


def test_matrix_pattern_holds_bulk_and_contact_couplings_without_mallocs():
    """The contact matrix is preallocated in one pass with the bulk pattern and the springs'
    couplings (explicit zeros kept): it holds both, adds entries between contact nodes only, and
    its assemblies never allocate."""
    problem, pressure, _ = _setup("hexahedron")
    solve_increments(problem, pressure, increments=1)
    A = problem.ensure_matrix()
    assert A.getInfo()["mallocs"] == 0
    assert A.getBlockSize() == 3
    indptr, indices, _ = A.getValuesCSR()
    n = A.getSize()[0] // 3
    got = scipy.sparse.csr_matrix((np.ones(indices.size), indices, indptr), shape=A.getSize())
    offsets, columns = compat.sparsity_graph(problem.a)
    bulk = scipy.sparse.csr_matrix((np.ones(columns.size), columns, offsets), shape=(n, n))
    rows, cols = [], []
    for state in problem.states:
        nodes = state.element_nodes
        rows.append(np.repeat(nodes, nodes.shape[1], axis=1).ravel())
        cols.append(np.tile(nodes, (1, nodes.shape[1])).ravel())
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    assert rows.size > 0
    contact = scipy.sparse.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    expected = scipy.sparse.kron((bulk + contact) > 0, np.ones((3, 3)), format="csr") > 0
    assert ((expected > 0).astype(int) - (got > 0).astype(int) > 0).nnz == 0  # all held
    # entries beyond the bulk pattern couple contact nodes only
    extra = ((got > 0).astype(int) - scipy.sparse.kron(bulk > 0, np.ones((3, 3))) > 0).tocoo()
    contact_dofs = np.zeros(A.getSize()[0], dtype=bool)
    for state in problem.states:
        contact_dofs[(3 * state.element_nodes[..., None] + np.arange(3)).ravel()] = True
    assert extra.nnz > 0
    assert contact_dofs[extra.row].all() and contact_dofs[extra.col].all()
