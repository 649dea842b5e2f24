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


def test_free_body_is_named():
    """A body with neither a Dirichlet condition nor a contact spring."""
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD, [[0, 0, 0], [1, 1, 1]], [3, 3, 3], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 1.0))
    tags = dolfinx.mesh.meshtags(mesh, 2, np.sort(top), np.full(top.size, 1, np.int32))
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    F = ufl.inner(ntf.small_strain_stress(u, 1e3, 0.3), ufl.grad(v)) * ufl.dx
    F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(1)
    problem = ntf.ContactProblem(F, u, [], [])
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    with pytest.raises(
        ntf.ContactSolverError,
        match=r"singular.*body 1 of 1 \(64 nodes, centroid \(0.5, 0.5, 0.5\)\) has no Dirichlet",
    ):
        _step(pressure, 1.0).run(solver, u)
    assert solver.updates == 0


def test_lower_block_without_support_is_named_among_two():
    """Two blocks: the punch is held, the block under it has no Dirichlet condition and no spring
    (a gap): the message names the second of the two bodies by its centroid."""
    problem, pressure, _ = punch_problem(gap=0.05)
    problem.set_bcs(problem.bcs[1:])  # drop the lower block's clamp, keep the punch's
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    with pytest.raises(ntf.ContactSolverError, match=r"singular.*body \d of 2 .* has no Dirichlet"):
        _step(pressure, 10.0).run(solver, problem.u)
