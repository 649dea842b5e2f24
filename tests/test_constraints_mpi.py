"""Linear constraints are serial only: refused on every process (run by ``make test`` on 2)."""

from mpi4py import MPI

import pytest

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.mpi


def test_constraints_run_on_one_process_only():
    comm = MPI.COMM_WORLD
    mesh = dolfinx.mesh.create_unit_cube(comm, 2, 2, 2, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    # constraints given on rank 0 only: every process must stop, none may wait alone
    tie = [ntf.LinearConstraint([0, 1], [2, 2], [1.0, -1.0])] if comm.rank == 0 else []
    if comm.size == 1:
        assert ntf.ContactProblem(F, u, [], constraints=tie).elimination.num_constraints == 1
    else:
        with pytest.raises(NotImplementedError, match=f"constraints on {comm.size} MPI processes"):
            ntf.ContactProblem(F, u, [], constraints=tie)
