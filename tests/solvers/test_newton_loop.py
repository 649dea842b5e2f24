"""Our Newton loop (solvers/newton_loop.py) against dolfinx's own NewtonSolver, where it exists."""

import warnings

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.solvers.newton_loop import NewtonSolver

pytestmark = pytest.mark.mpi


def _dolfinx_newton():
    """dolfinx's NewtonSolver and its problem class, or skip where dolfinx has removed them."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        try:
            import dolfinx.nls.petsc
        except ImportError:
            pytest.skip("this dolfinx has no dolfinx.nls (nothing to compare with)")
    problem_class = getattr(
        dolfinx.fem.petsc, "NewtonSolverNonlinearProblem", dolfinx.fem.petsc.NonlinearProblem
    )
    return dolfinx.nls.petsc.NewtonSolver, problem_class


@pytest.fixture(scope="module")
def mesh():
    """One mesh for both solvers: in parallel two meshes may number their dofs differently."""
    return dolfinx.mesh.create_unit_square(MPI.COMM_WORLD, 12, 12)


def _nonlinear_poisson(mesh, problem_class):
    """-div((1 + u^2) grad u) = 10 on the unit square, u = 0 on the boundary."""
    V = compat.scalar_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner((1 + u**2) * ufl.grad(u), ufl.grad(v)) * ufl.dx - 10.0 * v * ufl.dx
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 1, lambda x: np.full(x.shape[1], True))
    dofs = dolfinx.fem.locate_dofs_topological(V, 1, facets)
    bc = dolfinx.fem.dirichletbc(np.float64(0.0), dofs, V)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        problem = problem_class(F, u, bcs=[bc])
    return problem, u


def _run(mesh, solver_class, problem_class, **settings):
    """Solve, recording the norm of every iterate the solver evaluates at."""
    problem, u = _nonlinear_poisson(mesh, problem_class)
    iterates = []
    form = problem.form

    def recording_form(x):
        form(x)
        iterates.append(x.norm())

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        solver = solver_class(MPI.COMM_WORLD, problem)
    solver.set_form(recording_form)
    for name, value in settings.items():
        setattr(solver, name, value)
    solver.krylov_solver.setType("preonly")
    solver.krylov_solver.getPC().setType("lu")
    iterations, converged = solver.solve(u)
    return iterations, converged, np.array(iterates), u.x.array.copy()


@pytest.mark.parametrize(
    "settings",
    [
        {"rtol": 1e-10, "atol": 1e-12},
        {"convergence_criterion": "incremental", "rtol": 1e-9, "atol": 1e-12},
        {"relaxation_parameter": 0.7, "rtol": 1e-8, "atol": 1e-12},
    ],
)
def test_same_iterates_as_dolfinx(mesh, settings):
    dolfinx_solver, problem_class = _dolfinx_newton()
    ours = _run(mesh, NewtonSolver, problem_class, **settings)
    theirs = _run(mesh, dolfinx_solver, problem_class, **settings)
    assert ours[:2] == theirs[:2]
    assert ours[1] and ours[0] >= 3
    assert np.allclose(ours[2], theirs[2], rtol=1e-13, atol=0.0)
    assert np.allclose(ours[3], theirs[3], rtol=0.0, atol=1e-13 * np.abs(theirs[3]).max())


def test_nonconvergence_raises_or_returns_false(mesh):
    _, problem_class = _dolfinx_newton()
    with pytest.raises(RuntimeError, match="maximum number of iterations"):
        _run(mesh, NewtonSolver, problem_class, max_it=1, rtol=1e-12, atol=1e-14)
    iterations, converged, _, _ = _run(
        mesh,
        NewtonSolver,
        problem_class,
        max_it=1,
        rtol=1e-12,
        atol=1e-14,
        error_on_nonconvergence=False,
    )
    assert (iterations, converged) == (1, False)


def test_unknown_criterion_is_named(mesh):
    _, problem_class = _dolfinx_newton()
    with pytest.raises(
        ValueError, match="convergence_criterion must be 'residual' or 'incremental'"
    ):
        _run(mesh, NewtonSolver, problem_class, convergence_criterion="energy")
