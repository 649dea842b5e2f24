"""2D contact on quadrilateral meshes: the node-to-segment springs on quad4 and quad9 edges.

The springs see only the boundary edges (line2 on quad4, line3 on quad9), so quadrilaterals need
nothing of their own; the patch test checks it: two blocks of quadrilaterals (gmsh's recombined
transfinite rectangles, and dolfinx's own quadrilaterals built from points and cells), a uniform
pressure on the upper one, transmitted as a uniform contact pressure to 1e-8 on matching meshes.
gmsh's 8-node quadrilaterals (Mesh.SecondOrderIncomplete = 1) have no dolfinx mesh: refused with
a clear error by ``mesh_from_gmsh``.
"""

from __future__ import annotations

from mpi4py import MPI

import gmsh
import numpy as np
import pytest

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

E, NU, PRESSURE = 1000.0, 0.3, 10.0
LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, LOWER_BOTTOM, SYMMETRY = 3, 4, 5, 6, 7


def _build_quad_blocks(order: int, incomplete: bool = False) -> None:
    """A 1 x 0.4 block on a 1 x 0.5 block, recombined quadrilaterals of order 1 or 2."""
    gmsh.model.add("quad_blocks_2d")
    g = gmsh.model.geo
    surfaces, lines = [], []
    for (y0, y1), (nx, ny) in (((-0.5, 0.0), (4, 2)), ((0.0, 0.4), (4, 2))):
        p = [g.addPoint(0, y0, 0), g.addPoint(1, y0, 0), g.addPoint(1, y1, 0), g.addPoint(0, y1, 0)]
        edges = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
        surface = g.addPlaneSurface([g.addCurveLoop(edges)])
        for edge, n in zip(edges, (nx, ny, nx, ny)):
            g.mesh.setTransfiniteCurve(edge, n + 1)
        g.mesh.setTransfiniteSurface(surface)
        g.mesh.setRecombine(2, surface)
        surfaces.append(surface)
        lines.append(edges)
    g.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(2, [surfaces[0]], 1)
    model.addPhysicalGroup(2, [surfaces[1]], 2)
    model.addPhysicalGroup(1, [lines[0][2]], LOWER_TOP)
    model.addPhysicalGroup(1, [lines[1][0]], UPPER_BOTTOM)
    model.addPhysicalGroup(1, [lines[1][2]], UPPER_TOP)
    model.addPhysicalGroup(1, [lines[0][0]], LOWER_BOTTOM)
    model.addPhysicalGroup(1, [lines[0][3], lines[1][3]], SYMMETRY)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", int(incomplete))
    model.mesh.generate(2)
    model.mesh.setOrder(order)


def _dolfinx_quad_blocks(comm):
    """The same blocks as dolfinx quadrilaterals from points and cells (no gmsh)."""
    points, cells = [], []
    for y0, height in ((-0.5, 0.5), (0.0, 0.4)):
        x, y = np.meshgrid(np.linspace(0, 1, 5), np.linspace(y0, y0 + height, 3))
        i, j = np.meshgrid(np.arange(4), np.arange(2))
        a = (j * 5 + i).ravel() + sum(len(p) for p in points)
        cells.append(np.column_stack([a, a + 1, a + 5, a + 6]))  # dolfinx's tensor order
        points.append(np.column_stack([x.ravel(), y.ravel()]))
    points, cells = np.vstack(points), np.vstack(cells).astype(np.int64)
    if comm.rank != 0:
        points, cells = np.empty((0, 2)), np.empty((0, 4), dtype=np.int64)
    element = compat.coordinate_element("quadrilateral", 1, gdim=2)
    mesh = compat.create_mesh(comm, cells, points, element, None)
    mesh.topology.create_connectivity(1, 2)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    num_cells = mesh.topology.index_map(2).size_local + mesh.topology.index_map(2).num_ghosts
    cell_y = dolfinx.mesh.compute_midpoints(mesh, 2, np.arange(num_cells, dtype=np.int32))[:, 1]
    f_to_c = mesh.topology.connectivity(1, 2)
    upper = cell_y[f_to_c.array[f_to_c.offsets[exterior]]] > 0.0
    x, y = dolfinx.mesh.compute_midpoints(mesh, 1, exterior)[:, :2].T
    values = np.zeros(exterior.size, dtype=np.int32)
    values[~upper & np.isclose(y, -0.5)] = LOWER_BOTTOM
    values[~upper & np.isclose(y, 0.0)] = LOWER_TOP
    values[upper & np.isclose(y, 0.0)] = UPPER_BOTTOM
    values[upper & np.isclose(y, 0.4)] = UPPER_TOP
    values[np.isclose(x, 0.0)] = SYMMETRY
    keep = values > 0
    order = np.argsort(exterior[keep])
    return mesh, dolfinx.mesh.meshtags(mesh, 1, exterior[keep][order], values[keep][order])


def _patch(mesh, facet_tags, degree):
    """Press the upper block with PRESSURE; returns the pair's state after the step."""
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    F += load * ufl.inner(ufl.FacetNormal(mesh), v) * ds(UPPER_TOP)
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, UPPER_BOTTOM),
        ntf.FacetSurface(facet_tags, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw(slope=1e4 * E, tension=E / 70000)),
    )
    bcs = [
        component_bc(V, 0, facet_tags.find(SYMMETRY)),
        component_bc(V, 1, facet_tags.find(LOWER_BOTTOM)),
    ]
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    step = ntf.StaticStep(lambda t: setattr(load, "value", PRESSURE * t), initial_increment=0.5)
    results = step.run(solver, u)
    solver.destroy()
    return problem, results


def _assert_uniform(problem, results, springs: int, edge_nodes: int) -> None:
    comm = problem.u.function_space.mesh.comm
    assert all(r.iterations <= 3 for r in results)
    state = problem.states[0]
    assert state.master_faces.face_type.num_nodes == edge_nodes
    (table,) = ntf.contact_results(problem)
    pressure = np.concatenate(comm.allgather(table.pressure))
    assert pressure.size == springs
    np.testing.assert_allclose(pressure, pressure.mean(), rtol=1e-8)
    assert pressure.mean() == pytest.approx(PRESSURE, rel=1e-2)  # load over the current length
    assert ntf.contact_force(problem)[1] == pytest.approx(PRESSURE, rel=1e-10)  # width 1


@pytest.mark.serial
@pytest.mark.parametrize(
    ("order", "degree", "springs", "edge_nodes"),
    [(1, 1, 5, 2), (1, 2, 9, 3), (2, 2, 9, 3)],
    ids=["quad4-P1", "quad4-P2", "quad9-P2"],
)
def test_patch_test_on_gmsh_quadrilaterals(order, degree, springs, edge_nodes):
    """Recombined gmsh quadrilaterals, straight (quad4) or second order (quad9)."""
    mesh, _, facet_tags = mesh_from_gmsh(_build_quad_blocks, gdim=2, order=order)
    assert mesh.topology.cell_type == dolfinx.mesh.CellType.quadrilateral
    assert compat.geometry_dofs(mesh).shape[1] == (4 if order == 1 else 9)
    problem, results = _patch(mesh, facet_tags, degree)
    _assert_uniform(problem, results, springs, edge_nodes)


@pytest.mark.serial
def test_gmsh_quad8_is_refused_clearly():
    """8-node (serendipity) quadrilaterals: dolfinx has no such mesh; a ValueError says so."""
    with pytest.raises(ValueError, match=r"8-node quadrilaterals.*SecondOrderIncomplete = 0"):
        mesh_from_gmsh(_build_quad_blocks, gdim=2, order=2, incomplete=True)


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
def test_patch_test_on_dolfinx_quadrilaterals(degree):
    """dolfinx's quadrilaterals (tensor-ordered cells), on one or several processes."""
    mesh, facet_tags = _dolfinx_quad_blocks(MPI.COMM_WORLD)
    assert mesh.topology.cell_type == dolfinx.mesh.CellType.quadrilateral
    problem, results = _patch(mesh, facet_tags, degree)
    _assert_uniform(problem, results, 4 * degree + 1, degree + 1)
