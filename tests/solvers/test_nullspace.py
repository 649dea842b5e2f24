"""Rigid-body near-nullspace per body and the iterative linear solver (docs/method.md §14.7).

The ``mpi`` tests also run on 2 processes (``make test``), with a partition cut through the
contact zone.
"""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
from helpers import LOWER_TOP, elastic_residual, punch_problem

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.solvers import linear_solver, nullspace

COMM = MPI.COMM_WORLD
LOAD = 20.0


def _cut(x):
    """Slices along x: every cut crosses the contact zone."""
    return np.minimum((x[:, 0] * COMM.size).astype(int), COMM.size - 1)


def _rigid_fit(points, values):
    """Largest misfit of ``values`` (n, 3) by a rigid motion a + w x r, least squares."""
    n = points.shape[0]
    basis = np.zeros((n, 3, 6))
    basis[:, 0, 0] = basis[:, 1, 1] = basis[:, 2, 2] = 1.0
    x, y, z = points.T
    basis[:, 1, 3], basis[:, 2, 3] = -z, y
    basis[:, 0, 4], basis[:, 2, 4] = z, -x
    basis[:, 0, 5], basis[:, 1, 5] = -y, x
    basis = basis.reshape(3 * n, 6)
    coefficients, *_ = np.linalg.lstsq(basis, values.ravel(), rcond=None)
    return np.abs(basis @ coefficients - values.ravel()).max()


def test_connected_components():
    """Cells sharing a node join; extra links join too; lone nodes are their own component."""
    cells = np.array([[0, 1], [1, 2], [3, 4]])
    count, labels = nullspace.connected_components(cells, 6)
    assert count == 3
    assert labels[0] == labels[1] == labels[2] != labels[3] == labels[4] != labels[5]
    count, labels = nullspace.connected_components(cells, 6, links=np.array([[2, 3]]))
    assert count == 2 and len(set(labels[:5])) == 1


def test_rigid_body_modes_pure():
    """6 orthonormal columns per body, zero outside it, each a rigid motion of its body."""
    rng = np.random.default_rng(3)
    points = rng.random((40, 3)) * [2.0, 1.0, 0.5] + [10.0, 0.0, 0.0]  # far from the origin
    bodies = (points[:, 0] > 11.0).astype(np.int64)
    modes = nullspace.rigid_body_modes(points, bodies, 2)
    assert modes.shape == (120, 12)
    np.testing.assert_allclose(modes.T @ modes, np.eye(12), atol=1e-13)
    for b in range(2):
        for column in modes[:, 6 * b : 6 * b + 6].T:
            field = column.reshape(-1, 3)
            assert np.abs(field[bodies != b]).max() == 0.0
            assert _rigid_fit(points[bodies == b], field[bodies == b]) < 1e-13


@pytest.mark.mpi
def test_near_nullspace_of_the_punch():
    """Two bodies (touching only through contact): 12 orthonormal vectors, each a rigid motion
    of one body: its elastic residual vanishes (to round-off of the residual of a deformation)."""
    problem, _, ft = punch_problem(comm=COMM, partition=_cut)
    V = problem.u.function_space
    num_bodies, body = nullspace.body_numbers(V)
    assert num_bodies == 2
    space = nullspace.near_nullspace(V)
    vectors = space.getVecs()
    assert len(vectors) == 6 * num_bodies
    gram = np.array([[a.dot(b) for b in vectors] for a in vectors])
    np.testing.assert_allclose(gram, np.eye(12), atol=1e-13)

    u = dolfinx.fem.Function(V)
    residual = dolfinx.fem.form(elastic_residual(u, ufl.TestFunction(V), ft, 0.0))
    owned = V.dofmap.index_map.size_local

    def residual_norm(values):
        u.x.array[: 3 * owned] = values
        u.x.scatter_forward()
        b = dolfinx.fem.petsc.assemble_vector(residual)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        norm = b.norm()
        b.destroy()
        return norm

    points = V.tabulate_dof_coordinates()[:owned]
    bent = np.zeros((owned, 3))
    bent[:, 2] = points[:, 0] ** 2  # a deformation of the same size as the modes
    scale = residual_norm(bent.ravel() / np.sqrt(COMM.allreduce((bent**2).sum())))
    for k, vector in enumerate(vectors):
        values = vector.array_r.copy()  # read-only in the null space (PETSc 3.22)
        field = values.reshape(-1, 3)
        other = body[:owned] != k // 6
        assert np.abs(field[other]).max(initial=0.0) == 0.0  # zero outside its body
        assert residual_norm(values) < 1e-12 * scale
    space.destroy()
    problem.destroy()


def _solve(linear_solver, **options):
    problem, pressure, _ = punch_problem(comm=COMM, partition=_cut, **options)
    solver = ntf.ContactNewtonSolver(COMM, problem, linear_solver=linear_solver)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    ksp = solver.krylov_solver
    out = (
        problem.u.x.array.copy(),
        [r.iterations for r in results],
        (ksp.getType(), ksp.getPC().getType()),
        solver.near_nullspace is not None
        # the matrix the solves used (created at the first pairing) carries the modes
        and ksp.getOperators()[0].getNearNullSpace().handle == solver.near_nullspace.handle,
    )
    solver.destroy()
    problem.destroy()
    return out


@pytest.mark.mpi
@pytest.mark.parametrize("symmetric", [False, True])
def test_iterative_solver_gives_the_direct_answer(symmetric):
    """GMRES (CG when symmetric) + GAMG with the per-body modes converges, with contact springs
    and Dirichlet rows, to MUMPS's answer in the same Newton iterations.

    Each linear solve leaves a relative residual below ksp_rtol = 1e-10; the converged
    displacements of both runs satisfy the same force test (TIGHT controls, 1e-10 of the forces),
    so they may differ by about the condition number of the tangent times 1e-10: 1e-8 relative
    is allowed (measured: 1e-15, the last Newton step is quadratic).
    """
    direct = _solve("direct", symmetric=symmetric)
    iterative = _solve("iterative", symmetric=symmetric)
    assert direct[2] == ("preonly", "cholesky" if symmetric else "lu") and not direct[3]
    assert iterative[2] == ("cg" if symmetric else "gmres", "gamg") and iterative[3]
    assert iterative[1] == direct[1]
    scale = COMM.allreduce(np.abs(direct[0]).max(), op=MPI.MAX)
    difference = COMM.allreduce(np.abs(iterative[0] - direct[0]).max(), op=MPI.MAX)
    assert difference < 1e-8 * scale


def test_auto_choice_and_prefix_override(monkeypatch):
    """The "auto" choice is direct up to DIRECT_MAX_DOFS, iterative above; options in PETSc's
    database under the solver's prefix take precedence and are left there."""
    problem, _, ft = punch_problem()
    solver = ntf.ContactNewtonSolver(COMM, problem)
    assert solver.krylov_solver.getPC().getType() == "lu" and solver.near_nullspace is None
    solver.destroy()
    monkeypatch.setattr(linear_solver, "DIRECT_MAX_DOFS", 100)
    solver = ntf.ContactNewtonSolver(COMM, problem)
    assert solver.krylov_solver.getType() == "gmres"
    assert solver.krylov_solver.getPC().getType() == "gamg" and solver.near_nullspace is not None
    solver.destroy()
    options = PETSc.Options()
    options["ntftest_ksp_rtol"] = 1e-12
    options["ntftest_pc_type"] = "gamg"
    try:
        solver = ntf.ContactNewtonSolver(
            COMM, problem, linear_solver="iterative", options_prefix="ntftest_"
        )
        assert solver.krylov_solver.getTolerances()[0] == pytest.approx(1e-12)
        solver.destroy()
        solver = ntf.ContactNewtonSolver(
            COMM, problem, linear_solver="direct", options_prefix="ntftest_"
        )
        ksp = solver.krylov_solver
        assert ksp.getType() == "preonly" and ksp.getPC().getType() == "gamg"
        assert solver.near_nullspace is not None  # any GAMG gets the modes
        solver.destroy()
        assert options.getReal("ntftest_ksp_rtol") == pytest.approx(1e-12)
    finally:
        options.delValue("ntftest_ksp_rtol")
        options.delValue("ntftest_pc_type")
    with pytest.raises(ValueError, match="linear_solver must be one of"):
        ntf.ContactNewtonSolver(COMM, problem, linear_solver="cg")
    V = problem.u.function_space
    low = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_TOP))  # not clamped
    tie = ntf.LinearConstraint([int(low[0]), int(low[1])], [2, 2], [1.0, -1.0], name="tie")
    problem.destroy()
    problem, _, _ = punch_problem(constraints=[tie])  # reduced matrix: no rigid modes, direct
    solver = ntf.ContactNewtonSolver(COMM, problem)
    assert solver.krylov_solver.getPC().getType() == "lu"
    solver.destroy()
    problem.destroy()


def test_near_nullspace_needs_a_3d_vector_space():
    """A scalar space is refused with a message naming what is wrong."""
    problem, _, _ = punch_problem()
    V = compat.scalar_space(problem.u.function_space.mesh, "Lagrange", 1)
    with pytest.raises(ValueError, match="3D vector space"):
        nullspace.near_nullspace(V)
    problem.destroy()
