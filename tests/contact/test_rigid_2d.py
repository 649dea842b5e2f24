"""Rigid masters on 2D meshes: a line (half-plane) and a circle (docs/method.md §15.1).

Closed forms: a block pressed onto a rigid line carries its load as a uniform pressure and is
compressed by ``p (1 - nu^2) h / E`` (plane strain, no lateral stress); an elastic cylinder on a
rigid line and a rigid circle pressed into an elastic block follow Hertz's line contact with
``E* = E / (1 - nu^2)``. A rigid surface that depends on z is refused.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import tagged_block

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem import measures
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import cylinder
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

pytestmark = pytest.mark.serial

E, NU = 1000.0, 0.3
E_STAR = E / (1 - NU**2)  # an elastic body on a rigid one
PRESSURE, HEIGHT = 10.0, 0.4
BOTTOM, TOP, LEFT = 1, 2, 3
LAW = ntf.LinearLaw(slope=1e4 * E, tension=E / 70000)


def _block(degree: int):
    """The block [0, 1] x [0, HEIGHT] (4 x 2 squares, 2 triangles each) with its edge tags."""
    mesh, ft = tagged_block(HEIGHT, MPI.COMM_SELF, tags=(BOTTOM, TOP, LEFT))
    return mesh, ft, compat.vector_space(mesh, "Lagrange", degree)


def _solve(problem, constant, value, increment):
    solver = ntf.ContactNewtonSolver(MPI.COMM_SELF, problem)
    step = ntf.StaticStep(
        lambda t: setattr(constant, "value", value * t), initial_increment=increment
    )
    results = step.run(solver, problem.u)
    solver.destroy()
    return results


@pytest.mark.parametrize("degree", [1, 2])
def test_block_on_a_rigid_line_is_a_patch_test(degree: int) -> None:
    """Uniform pressure p/(1 + lateral strain), force p, compression p (1 - nu^2) h / E."""
    mesh, ft, V = _block(degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += load * ufl.inner(ufl.FacetNormal(mesh), v) * ds(TOP)
    line = ntf.RigidPlane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, BOTTOM), line, ntf.SurfaceInteraction(LAW))
    problem = ntf.ContactProblem(F, u, [pair], [component_bc(V, 0, ft.find(LEFT))])
    results = _solve(problem, load, PRESSURE, 0.5)
    assert all(r.iterations <= 4 for r in results)
    (res,) = ntf.contact_results(problem)
    assert res.node.size == 4 * degree + 1
    lateral = NU * (1 + NU) * PRESSURE / E
    np.testing.assert_allclose(res.pressure, PRESSURE / (1 + lateral), rtol=1e-8)
    np.testing.assert_allclose(res.normal, np.tile([0.0, 1.0], (res.node.size, 1)), atol=1e-14)
    force = ntf.contact_force(problem)
    assert force[1] == pytest.approx(PRESSURE, rel=1e-10) and abs(force[0]) < 1e-10
    assert ntf.contact_area(problem) == pytest.approx(1 + lateral, rel=1e-9)
    # the springs' overlap is the law's for the pressure; the block's compression is elastic
    depth = -res.clearance
    np.testing.assert_allclose(LAW.spring_force(depth, res.area)[0] / res.area, res.pressure)
    uy = u.x.array.reshape(-1, 2)[:, 1]
    y = V.tabulate_dof_coordinates()[:, 1]
    np.testing.assert_allclose(uy[np.isclose(y, 0.0)], -depth.mean(), rtol=1e-8)
    compression = uy[np.isclose(y, 0.0)].mean() - uy[np.isclose(y, HEIGHT)].mean()
    assert compression == pytest.approx(PRESSURE * (1 - NU**2) * HEIGHT / E, rel=1e-8)


def _hertz(line_load: float, radius: float = 1.0) -> tuple[float, float]:
    """(b, p0) of plane-strain Hertz for the line load F' (the whole cylinder)."""
    b = np.sqrt(4 * line_load * radius / (np.pi * E_STAR))
    return float(b), float(2 * line_load / (np.pi * b))


def _fit(problem, b: float, p0: float) -> tuple[float, float]:
    """Hertz's profile fitted to the nodal pressures over the slave nodes' reference x."""
    state = problem.states[0]
    pressure = ntf.ContactFields(problem).at_nodes(state.slave.nodes)[0]
    x = problem.u.function_space.tabulate_dof_coordinates()[state.slave.nodes, 0]
    return measures.fit_hertz_profile(x, pressure, b, p0)


HALF_WIDTH = 0.05


def test_cylinder_on_a_rigid_line_follows_hertz() -> None:
    """Half cylinder (R = 1) by a line load on the line y = 0: b within 1 %, p0 within 2 %."""
    line_load = np.pi * E_STAR * HALF_WIDTH**2 / 4
    mesh, _, ft = mesh_from_gmsh(
        cylinder.build_cylinder_on_block,
        MPI.COMM_SELF,
        gdim=2,
        bodies="cylinder",
        size_fine=HALF_WIDTH / 10,
        refine_distance=2.5 * HALF_WIDTH,
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += load / 2 * v[1] * ds(cylinder.CYLINDER_TOP)  # half the line load over the width R
    line = ntf.RigidPlane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0))
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cylinder.CYLINDER_CONTACT), line, ntf.SurfaceInteraction(LAW)
    )
    problem = ntf.ContactProblem(F, u, [pair], [component_bc(V, 0, ft.find(cylinder.SYMMETRY))])
    results = _solve(problem, load, line_load, 0.25)
    assert sum(r.iterations for r in results) <= 40
    assert ntf.contact_force(problem)[1] == pytest.approx(line_load / 2, rel=1e-8)
    b, p0 = _hertz(line_load)
    b_fit, p0_fit = _fit(problem, b, p0)
    assert b_fit == pytest.approx(b, rel=1e-2)
    assert p0_fit == pytest.approx(p0, rel=2e-2)


def test_rigid_circle_pressed_into_a_block_follows_hertz() -> None:
    """A rigid circle (a cylinder along z) moved 0.006 R into the block: Hertz for its force."""
    radius, depth = 1.0, 0.006
    mesh, _, ft = mesh_from_gmsh(
        cylinder.build_cylinder_on_block,
        MPI.COMM_SELF,
        gdim=2,
        bodies="block",
        size_fine=HALF_WIDTH / 10,
        refine_distance=2.5 * HALF_WIDTH,
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    position = dolfinx.fem.Constant(mesh, 0.0)  # the relative step time drives the motion

    circle = ntf.RigidCylinder(
        point=(0.0, radius, 0.0),
        axis=(0.0, 0.0, 1.0),
        radius=radius,
        motion=lambda t: (0.0, -depth * t, 0.0),
    )
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cylinder.BLOCK_TOP), circle, ntf.SurfaceInteraction(LAW)
    )
    bottom = ft.find(cylinder.BLOCK_BOTTOM)
    bcs = [
        component_bc(V, 0, ft.find(cylinder.SYMMETRY)),
        component_bc(V, 0, bottom),
        component_bc(V, 1, bottom),
    ]
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    results = _solve(problem, position, 1.0, 0.25)
    assert sum(r.iterations for r in results) <= 40
    force = ntf.contact_force(problem)
    support = ntf.reaction(problem, bottom)
    assert support[1] == pytest.approx(-force[1], rel=1e-8)  # the block pushed down
    line_load = -2 * force[1]  # on the block (slave), downwards; the whole cylinder
    b, p0 = _hertz(line_load, radius)
    assert b == pytest.approx(HALF_WIDTH, rel=0.3)  # the depth makes b about R/20
    b_fit, p0_fit = _fit(problem, b, p0)
    assert b_fit == pytest.approx(b, rel=2e-2)
    assert p0_fit == pytest.approx(p0, rel=2e-2)
    # the normals point from the circle's centre to the slave nodes
    (res,) = ntf.contact_results(problem)
    centre = np.array([0.0, radius - depth])
    radial = res.position - centre
    np.testing.assert_allclose(
        res.normal, radial / np.linalg.norm(radial, axis=1)[:, None], atol=1e-12
    )


@pytest.mark.parametrize(
    ("surface", "message"),
    [
        (ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 0.6, 0.8)), "the plane's normal"),
        (ntf.RigidCylinder((0.0, 2.0, 0.0), (1.0, 0.0, 0.0), 1.0), "the cylinder's axis"),
        (ntf.RigidSphere((0.0, 2.0, 0.5), 1.0), "the sphere's centre"),
    ],
)
def test_a_rigid_surface_out_of_the_plane_is_refused(surface, message) -> None:
    _, ft, V = _block(1)
    u = dolfinx.fem.Function(V)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    pair = ntf.ContactPair(ntf.FacetSurface(ft, BOTTOM), surface, ntf.SurfaceInteraction(LAW))
    with pytest.raises(ValueError, match=f"pair 1 master: on a 2D mesh .*{message}"):
        ntf.ContactProblem(F, u, [pair])


def test_a_signed_distance_that_depends_on_z_is_refused_when_evaluated() -> None:
    """A general surface is checked by its normal at the slave nodes."""
    tilted = np.array([0.0, 0.6, 0.8])
    surface = ntf.SignedDistanceSurface(
        lambda x: x @ tilted, lambda x: np.tile(tilted, (x.shape[0], 1))
    )
    mesh, ft, V = _block(1)
    u = dolfinx.fem.Function(V)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    pair = ntf.ContactPair(ntf.FacetSurface(ft, BOTTOM), surface, ntf.SurfaceInteraction(LAW))
    problem = ntf.ContactProblem(F, u, [pair], [component_bc(V, 0, ft.find(LEFT))])
    with pytest.raises(ValueError, match=r"must not depend on z.*z component 0\.8"):
        _solve(problem, dolfinx.fem.Constant(mesh, 0.0), 0.0, 1.0)
