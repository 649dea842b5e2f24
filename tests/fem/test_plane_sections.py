"""Per-cell 2D formulations (``fem.plane_sections.PlaneSections``, docs/method.md §26).

A unit square at radius ``R0`` split into axisymmetric cells (x < R0 + 0.5) and plane-stress
cells of thickness ``t`` (the rest): the weight integrates to the ring volume plus the plane
volume, a homogeneous finite-strain state has ``S_zz = 0`` on the plane-stress cells, and the
Jacobian of the St.Venant-Kirchhoff residual is its central difference. Scalars and norms only:
the same on any number of processes.
"""

from __future__ import annotations

import math

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.plane_sections import PlaneSections

pytestmark = pytest.mark.mpi

R0, T, MU, LMBDA = 2.0, 0.3, 80.0, 120.0


def _mesh() -> dolfinx.mesh.Mesh:
    return dolfinx.mesh.create_rectangle(
        MPI.COMM_WORLD,
        [np.array([R0, 0.0]), np.array([R0 + 1.0, 1.0])],
        [4, 4],
        dolfinx.mesh.CellType.quadrilateral,
    )


def _sections(mesh: dolfinx.mesh.Mesh) -> PlaneSections:
    tdim = mesh.topology.dim
    index_map = mesh.topology.index_map(tdim)
    cells = np.arange(index_map.size_local + index_map.num_ghosts, dtype=np.int32)
    midpoints = dolfinx.mesh.compute_midpoints(mesh, tdim, cells)
    axi = cells[midpoints[:, 0] < R0 + 0.5]
    return PlaneSections.from_cells(
        mesh, axisymmetric=axi, plane_stress=np.setdiff1d(cells, axi), thickness=T
    )


def _integral(expression: ufl.core.expr.Expr, mesh: dolfinx.mesh.Mesh) -> float:
    dx = ufl.dx(domain=mesh, metadata={"quadrature_degree": 6})
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(expression * dx))
    return mesh.comm.allreduce(local, op=MPI.SUM)


def test_weight_is_ring_volume_plus_plane_volume():
    mesh = _mesh()
    sections = _sections(mesh)
    ring = math.pi * ((R0 + 0.5) ** 2 - R0**2)  # 2 pi int r dr over [R0, R0 + 0.5], height 1
    assert _integral(sections.weight(), mesh) == pytest.approx(ring + 0.5 * T, rel=1e-12)
    assert _integral(sections.axisymmetric, mesh) == pytest.approx(0.5, rel=1e-12)


def test_finite_strain_plane_stress_has_no_out_of_plane_stress():
    """A homogeneous stretch: S_zz = 0 on plane-stress cells, the hoop stretch on the others."""
    mesh = _mesh()
    sections = _sections(mesh)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack([0.05 * x[0] + 0.02 * x[1], -0.03 * x[1]]))
    F = sections.deformation_gradient(u, MU, LMBDA)
    E = 0.5 * (F.T * F - ufl.Identity(3))
    S = 2 * MU * E + LMBDA * ufl.tr(E) * ufl.Identity(3)
    plane = 1 - sections.axisymmetric
    assert abs(_integral(plane * S[2, 2] ** 2, mesh)) < 1e-24
    assert _integral(plane * S[0, 0] ** 2, mesh) > 1.0  # stressed
    r = ufl.SpatialCoordinate(mesh)[0]
    hoop = sections.axisymmetric * (F[2, 2] - (1 + u[0] / r)) ** 2
    assert abs(_integral(hoop, mesh)) < 1e-28


def test_finite_strain_jacobian_is_the_central_difference():
    mesh = _mesh()
    sections = _sections(mesh)
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    u.interpolate(lambda x: np.vstack([0.04 * np.sin(x[1] + x[0]), 0.03 * x[0] * x[1]]))
    F = sections.deformation_gradient(u, MU, LMBDA)
    E = 0.5 * (F.T * F - ufl.Identity(3))
    P = F * (2 * MU * E + LMBDA * ufl.tr(E) * ufl.Identity(3))
    dx = ufl.dx(metadata={"quadrature_degree": 6})
    residual = ufl.inner(P, sections.grad(v)) * sections.weight() * dx
    jacobian = dolfinx.fem.form(ufl.derivative(residual, u))
    form = dolfinx.fem.form(residual)
    A = dolfinx.fem.petsc.assemble_matrix(jacobian)
    A.assemble()
    rng = np.random.default_rng(7 + mesh.comm.rank)
    du = dolfinx.fem.Function(V)
    du.x.array[:] = 1e-2 * rng.standard_normal(du.x.array.size)
    du.x.scatter_forward()
    Jdu = A.createVecLeft()
    A.mult(compat.petsc_vector(du), Jdu)
    h = 1e-6
    base = u.x.array.copy()
    values = []
    for sign in (1.0, -1.0):
        u.x.array[:] = base + sign * h * du.x.array
        b = dolfinx.fem.petsc.assemble_vector(form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        values.append(b)
    difference = (values[0] - values[1]) / (2 * h)
    error = (difference - Jdu).norm()
    assert Jdu.norm() > 1.0
    assert error < 1e-6 * Jdu.norm()


def test_bad_cells_and_thicknesses_are_refused():
    mesh = _mesh()
    with pytest.raises(ValueError, match="both axisymmetric and plane stress"):
        PlaneSections.from_cells(mesh, axisymmetric=[0], plane_stress=[0])
    with pytest.raises(ValueError, match="outside"):
        PlaneSections.from_cells(mesh, axisymmetric=[10**6])
    with pytest.raises(ValueError, match="thickness of cell"):
        PlaneSections.from_cells(mesh, thickness=-1.0)
    cube = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 1, 1, 1)
    with pytest.raises(ValueError, match="needs a 2D mesh"):
        PlaneSections.from_cells(cube)
