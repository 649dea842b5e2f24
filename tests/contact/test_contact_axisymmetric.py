"""Axisymmetric node-to-segment contact: ring spring areas (``ContactPair(axisymmetric=True)``).

A solid cylinder pressed uniformly onto a coaxial block of the same radius (the patch test of
axisymmetry: the exact solution is a uniform stress, the contact pressure uniform to 1e-8 only if
the ring areas are the consistent shares of a uniform pressure), Hertz's sphere on a block
(``demos/hertz_axisymmetric.py`` at the 3D demo's mesh sizes), and the errors.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.demos import load_demo
from helpers.gmsh_blocks_2d import (
    LEFT,
    LOWER_BOTTOM,
    LOWER_TOP,
    UPPER_BOTTOM,
    UPPER_TOP,
    stacked_rectangles,
)
from helpers.jacobian_check import directional_derivative

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.axisymmetric import axisymmetric_grad, axisymmetric_stress, axisymmetric_weight
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

E, NU = 1000.0, 0.3
RADIUS = 1.0
AXIS = LEFT


def _build_cylinder_on_block(
    order: int, x0: float = 0.0, upper_radius: float = RADIUS, nx_upper: int = 5
) -> None:
    """Meridian section: a cylinder r <= R, 0 <= z <= 0.4 on a block r <= R, -0.5 <= z <= 0."""
    lower = (x0, -0.5, x0 + RADIUS, 0.0, 5, 2)
    stacked_rectangles(
        "cylinder_axisymmetric", lower, (x0, 0.0, x0 + upper_radius, 0.4, nx_upper, 2), order
    )


def _cylinder_problem(
    order: int,
    mesh_options=None,
    *,
    axisymmetric=True,
    radial_load=False,
    area_weights="consistent",
    **options,
):
    """Cylinder on block, slave the cylinder's bottom; the load p (1 + r) with ``radial_load``."""
    mesh, _, facet_tags = mesh_from_gmsh(
        _build_cylinder_on_block, gdim=2, order=order, **(mesh_options or {})
    )
    V = compat.vector_space(mesh, "Lagrange", order)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    n = ufl.FacetNormal(mesh)
    if axisymmetric:
        w = axisymmetric_weight(mesh)
        bulk = ufl.inner(axisymmetric_stress(u, E, NU), axisymmetric_grad(v)) * w * ufl.dx
    else:  # plane strain
        w = 1.0
        bulk = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    shape = 1.0 + ufl.SpatialCoordinate(mesh)[0] if radial_load else 1.0
    F = bulk + load * shape * ufl.inner(n, v) * w * ds(UPPER_TOP)
    bcs = [
        component_bc(V, 0, facet_tags.find(AXIS)),
        component_bc(V, 1, facet_tags.find(LOWER_BOTTOM)),
    ]
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, UPPER_BOTTOM),
        ntf.FacetSurface(facet_tags, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw(slope=1e4 * E, tension=E / 70000)),
        axisymmetric=axisymmetric,
        area_weights=area_weights,
    )
    return ntf.ContactProblem(F, u, [pair], bcs, **options), load


@pytest.mark.mpi
@pytest.mark.parametrize("order", [1, 2])
def test_patch_test_cylinder_on_block_axisymmetric(order: int) -> None:
    """Uniform pressure p: F_N/A uniform to 1e-8, the rings carry p pi R² to 1e-10.

    P2: the corner node on the axis has no ring area (its consistent share is 0) and no spring.
    On several processes each owns its slave nodes' springs: the sums are global.
    """
    comm = MPI.COMM_WORLD
    problem, load = _cylinder_problem(order)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(load, "value", 10.0 * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    assert all(r.iterations <= 3 for r in results)
    state = problem.states[0]
    ev = state.evaluation
    springs = comm.allreduce(state.num_springs)
    assert springs == (6 if order == 1 else 10)  # all slave nodes but a P2 axis corner
    if state.num_springs:
        normal, area, vertical = ev.normal_force, ev.area, ev.forces[:, -1, 1]
    else:
        normal, area, vertical = np.zeros(0), np.zeros(0), np.zeros(0)
    pressure = np.concatenate(comm.allgather(normal / area))
    np.testing.assert_allclose(pressure, pressure.mean(), rtol=1e-8)
    force = -comm.allreduce(vertical.sum())
    assert force == pytest.approx(10.0 * np.pi * RADIUS**2, rel=1e-10)
    # The areas are rings at the current radius: R grew by nu p R / E (uniform stress -p).
    current = RADIUS * (1 + NU * 10.0 / E)
    assert comm.allreduce(area.sum()) == pytest.approx(np.pi * current**2, rel=1e-6)
    assert pressure.mean() == pytest.approx(force / (np.pi * current**2), rel=1e-8)


@pytest.mark.serial
@pytest.mark.parametrize("axisymmetric", [True, False], ids=["axisymmetric", "plane_strain"])
@pytest.mark.parametrize("linearize_area", [False, True])
def test_global_jacobian_matches_finite_differences_2d(
    axisymmetric: bool, linearize_area: bool
) -> None:
    """The assembled 2D Jacobian is the derivative of the residual at a fixed pairing: areas held
    at their pairing values, or recomputed and linearized (linearize_area).

    A narrower cylinder (R 0.9, 4 edges) on the block (5 edges) under a load growing with r: the
    springs, areas and pressures differ from node to node.
    """
    problem, load = _cylinder_problem(
        1, {"upper_radius": 0.9, "nx_upper": 4}, axisymmetric=axisymmetric,
        radial_load=True, linearize_area=linearize_area,
    )  # fmt: skip
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(load, "value", 10.0 * t), initial_increment=1.0).run(
        solver, problem.u
    )
    assert problem.states[0].num_springs == 5
    check = directional_derivative(problem, amplitude=1e-3, h=1e-4, seed=1)
    np.testing.assert_allclose(check.product, check.difference, atol=1e-6 * check.contact_scale)


@pytest.mark.serial
def test_hertz_sphere_axisymmetric(tmp_path: Path) -> None:
    """The 3D demo's sphere, force and mesh size in axisymmetry: a within 1 %, p0 within 2 %.

    Measured (P1, h = 0.014 R at the contact, 2162 dofs): F = 3.43e5 N, a -0.40 %, p0 +0.85 %
    (fit), nodal maximum +0.26 %; the 3D quarter model of the same sizes: -0.60 %, +2.29 %.
    """
    demo = load_demo("hertz_axisymmetric")
    summary = demo.main(["--quiet", "--output", str(tmp_path)])
    assert summary["equilibrium_error"] < 1e-8
    assert summary["force"] == pytest.approx(3.43e5, rel=0.02)
    assert abs(summary["a_error"]) < 0.01
    assert abs(summary["p0_error"]) < 0.02
    assert abs(summary["p_max_error"]) < 0.05
    assert summary["a_last_closed"] < summary["a_hertz"] < summary["a_first_open"]
    assert summary["increments"] == 8 and max(summary["iterations"]) <= 8
    assert Path(summary["png"]).stat().st_size > 10_000


@pytest.mark.serial
def test_axisymmetric_pair_options_are_checked() -> None:
    _, _, facet_tags = mesh_from_gmsh(_build_cylinder_on_block, gdim=2, order=1)
    slave_master = (
        ntf.FacetSurface(facet_tags, UPPER_BOTTOM),
        ntf.FacetSurface(facet_tags, LOWER_TOP),
    )
    interaction = ntf.SurfaceInteraction(ntf.LinearLaw(1e4, 1e-2))
    with pytest.raises(ValueError, match="axisymmetric pair has no thickness"):
        ntf.ContactPair(*slave_master, interaction, axisymmetric=True, thickness=2.0)
    with pytest.raises(TypeError, match="axisymmetric"):
        ntf.ContactPair(*slave_master, interaction, axisymmetric="yes")
    with pytest.raises(ValueError, match="area_weights must be 'consistent' or 'ccx'"):
        ntf.ContactPair(*slave_master, interaction, axisymmetric=True, area_weights="sector")
    with pytest.raises(ValueError, match="linearize_area = True is not supported"):
        _cylinder_problem(1, area_weights="ccx", linearize_area=True)
    with pytest.raises(ValueError, match="fallback_area must be one of"):
        ntf.ContactPair(*slave_master, interaction, fallback_area="sector")
    with pytest.raises(TypeError, match="faceless"):
        ntf.NodeSurface(np.zeros(1, np.int32), faceless="yes")


@pytest.mark.serial
def test_axisymmetric_pair_refuses_3d_meshes_and_negative_radii() -> None:
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 2)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 1.0))
    bottom = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 0.0))
    facets = np.concatenate([top, bottom]).astype(np.int32)
    order = np.argsort(facets)
    values = np.concatenate([np.ones(top.size), 2 * np.ones(bottom.size)]).astype(np.int32)
    tags = dolfinx.mesh.meshtags(mesh, 2, facets[order], values[order])
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, 1),
        ntf.FacetSurface(tags, 2),
        ntf.SurfaceInteraction(ntf.LinearLaw(1e4, 1e-2)),
        axisymmetric=True,
    )
    with pytest.raises(ValueError, match="axisymmetric = True is for 2D meshes"):
        ntf.ContactProblem(F, u, [pair])
    pair = dataclasses.replace(pair, axisymmetric=False, fallback_area="ccx_ring")
    with pytest.raises(ValueError, match="fallback_area = 'ccx_ring' is for 2D meshes"):
        ntf.ContactProblem(F, u, [pair])
    # A meridian mesh reaching x < 0: the slave edges there are named.
    mesh2, _, facet_tags = mesh_from_gmsh(_build_cylinder_on_block, gdim=2, order=1, x0=-0.5)
    V2 = compat.vector_space(mesh2, "Lagrange", 1)
    u2, v2 = dolfinx.fem.Function(V2), ufl.TestFunction(V2)
    F2 = ufl.inner(small_strain_stress(u2, E, NU), ufl.grad(v2)) * ufl.dx
    pair2 = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, UPPER_BOTTOM),
        ntf.FacetSurface(facet_tags, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw(1e4, 1e-2)),
        axisymmetric=True,
    )
    with pytest.raises(ValueError, match=r"need r = x\[0\] >= 0; 3 slave edge\(s\) reach r < 0"):
        ntf.ContactProblem(F2, u2, [pair2])


@pytest.mark.serial
def test_axisymmetric_node_surface_with_midside_nodes_is_refused() -> None:
    """ccx's fallback area of a node surface's midside nodes is no ring area: a clear error."""
    mesh, _, facet_tags = mesh_from_gmsh(_build_cylinder_on_block, gdim=2, order=2)
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    bottom = facet_tags.find(UPPER_BOTTOM)
    vertices = np.unique(compat.incident_entities(mesh, bottom, 1, 0))
    for dim in (0, 1):  # dolfinx 0.9 locates dofs only with these computed
        mesh.topology.create_connectivity(dim, 2)
    vertex_dofs = dolfinx.fem.locate_dofs_topological(V, 0, vertices)
    midside = np.setdiff1d(dolfinx.fem.locate_dofs_topological(V, 1, bottom), vertex_dofs)
    assert midside.size == 5
    F = ufl.inner(axisymmetric_stress(u, E, NU), axisymmetric_grad(v)) * ufl.dx
    pair = ntf.ContactPair(
        ntf.NodeSurface(vertices, midside_nodes=midside),
        ntf.FacetSurface(facet_tags, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw(1e4, 1e-2)),
        axisymmetric=True,
    )
    with pytest.raises(NotImplementedError, match="cannot give the midside nodes"):
        ntf.ContactProblem(F, u, [pair])
