"""A quarter sphere pressed onto a block by fixed increments of a prescribed displacement, with
CalculiX's default penalty (K = 50 E): ccx converges on such decks, and so must the Python API
(line search, no predictor, unpaired penetrations paired before convergence)."""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.meshes import hertz
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

pytestmark = pytest.mark.serial

RADIUS, E, NU, DISPLACEMENT = 10.0, 210_000.0, 0.3, 0.3


def test_fixed_increments_converge_with_every_penetrating_node_paired():
    sizes = {key: value * RADIUS for key, value in hertz.COARSE.items()}
    mesh, _, ft = mesh_from_gmsh(hertz.build_hertz, MPI.COMM_WORLD, radius=RADIUS, **sizes)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(hertz.BLOCK_BOTTOM))
    Vz, _ = compat.component_space(V, 2)
    top_uz = dolfinx.fem.Function(Vz)
    top = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, ft.find(hertz.SPHERE_TOP))
    top_bc = dolfinx.fem.dirichletbc(top_uz, top, V.sub(2))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType), bottom, V),
        ntf.component_bc(V, 0, ft.find(hertz.SYMMETRY_X)),
        ntf.component_bc(V, 1, ft.find(hertz.SYMMETRY_Y)),
        top_bc,
    ]
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, hertz.SPHERE_CONTACT),
        ntf.FacetSurface(ft, hertz.BLOCK_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E)),
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    step = ntf.StaticStep(
        lambda t: top_uz.x.array.fill(-DISPLACEMENT * t), initial_increment=0.25, fixed=True
    )
    results = step.run(solver, u)
    assert len(results) == 4
    springs = [r.springs for r in results]
    assert springs == sorted(springs) and springs[0] > 0
    assert problem.unpaired_contacts() == 0
    # The quarter's contact force balances the reaction at the sphere's top.
    force = ntf.contact_force(problem)
    reaction = ntf.reaction(problem, dofs=top_bc)
    assert force[2] > 0
    assert reaction[2] == pytest.approx(-force[2], rel=1e-8)
