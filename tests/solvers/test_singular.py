"""A singular Jacobian stops the solve with an error that names the body nothing holds, serially
and in parallel (no cutbacks, no runaway iterate returned as converged)."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import punch_problem

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.mpi


def _step(pressure, load):
    return ntf.StaticStep(lambda t: setattr(pressure, "value", load * t))


def _free_cube(foundation: float = 0.0):
    """A unit cube with no Dirichlet condition, a pressure on its top and, if ``foundation`` >
    0, an elastic foundation of that stiffness on its bottom (which holds it)."""
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [3, 3, 3], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    faces = dolfinx.mesh.locate_entities_boundary(
        mesh, 2, lambda x: np.isclose(x[2], 1.0) | np.isclose(x[2], 0.0)
    )
    midpoints = dolfinx.mesh.compute_midpoints(mesh, 2, faces)
    values = np.where(midpoints[:, 2] > 0.5, 1, 2).astype(np.int32)
    tags = dolfinx.mesh.meshtags(mesh, 2, faces, values)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    F = ufl.inner(ntf.small_strain_stress(u, 1e3, 0.3), ufl.grad(v)) * ufl.dx
    F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(1)
    if foundation > 0:
        F += foundation * ufl.inner(u, v) * ds(2)
    return ntf.ContactProblem(F, u, [], []), pressure


@pytest.mark.parametrize("load", [1.0, 0.0])
def test_free_body_is_named(load):
    """A body with neither a Dirichlet condition nor a contact spring, loaded (the direct solve
    leaves the right-hand side unsolved) or not (u = 0 solves it: its rigid-body modes are null
    vectors of the Jacobian)."""
    problem, pressure = _free_cube()
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    with pytest.raises(
        ntf.ContactSolverError,
        match=r"singular.*body 1 of 1 \(64 nodes, centroid \(0.5, 0.5, 0.5\)\) has no Dirichlet",
    ):
        _step(pressure, load).run(solver, problem.u)
    assert solver.updates == 0


def test_body_on_elastic_foundation_is_held():
    """No Dirichlet condition, no spring, but an elastic foundation in the residual form: the
    Jacobian is regular, so the unloaded increment converges to u = 0 with no error."""
    problem, pressure = _free_cube(foundation=10.0)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    results = _step(pressure, 0.0).run(solver, problem.u)
    assert results[-1].time == 1.0
    assert np.abs(problem.u.x.array).max() == 0.0


def test_lower_block_without_support_is_named_among_two():
    """Two blocks: the punch is held, the block under it has no Dirichlet condition and no spring
    (a gap): the message names the second of the two bodies by its centroid."""
    problem, pressure, _ = punch_problem(gap=0.05)
    problem.set_bcs(problem.bcs[1:])  # drop the lower block's clamp, keep the punch's
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    with pytest.raises(ntf.ContactSolverError, match=r"singular.*body \d of 2 .* has no Dirichlet"):
        _step(pressure, 10.0).run(solver, problem.u)
