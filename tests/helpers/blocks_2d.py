"""Two rectangles stacked along y, triangulated without gmsh: the 2D patch test's blocks.

The lower block ``[0, 1] x [-0.5, 0]``, the upper one ``[0, 1] x [0, 0.4]`` touching it along
y = 0 with nodes of its own; rollers at x = 0 (both blocks) and under the lower block, a pressure
on the upper top. Plane strain, the residual per ``thickness`` (the pairs get the same).
``partition(midpoints)`` optionally gives the process of each cell (MPI tests).
"""

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress

LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, SYMMETRY = 1, 2, 3, 4, 5
YOUNGS_MODULUS, POISSON_RATIO = 1000.0, 0.3
PRESSURE = 10.0
#: Lateral strain of both blocks under PRESSURE (plane strain, sigma_xx = 0): nu (1 + nu) p / E.
LATERAL_STRAIN = POISSON_RATIO * (1 + POISSON_RATIO) * PRESSURE / YOUNGS_MODULUS


def rectangle_grid(origin, size, divisions):
    """Points (N, 2) and triangles (2 nx ny, 3) of a structured rectangle."""
    (x0, y0), (lx, ly), (nx, ny) = origin, size, divisions
    x, y = np.meshgrid(np.linspace(x0, x0 + lx, nx + 1), np.linspace(y0, y0 + ly, ny + 1))
    points = np.column_stack([x.ravel(), y.ravel()])
    i, j = np.meshgrid(np.arange(nx), np.arange(ny))
    a = (j * (nx + 1) + i).ravel()
    b, c, d = a + 1, a + nx + 2, a + nx + 1
    return points, np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])


def tagged_block(height: float, comm=MPI.COMM_WORLD, *, tags=(1, 2, 3)):
    """The block [0, 1] x [0, height] in 4 x 2 squares of 2 triangles (on rank 0 of ``comm``).

    Returns the mesh and its edge tags: ``tags`` = (bottom, top, left).
    """
    points, cells = rectangle_grid((0.0, 0.0), (1.0, height), (4, 2))
    if comm.rank != 0:
        points, cells = np.empty((0, 2)), np.empty((0, 3), dtype=np.int64)
    element = compat.coordinate_element("triangle", 1, gdim=2)
    mesh = compat.create_mesh(comm, cells.astype(np.int64), points, element)
    mesh.topology.create_connectivity(1, 2)
    facets, values = [], []
    for tag, where in zip(
        tags,
        (
            lambda x: np.isclose(x[1], 0.0),
            lambda x: np.isclose(x[1], height),
            lambda x: np.isclose(x[0], 0.0),
        ),
    ):
        found = dolfinx.mesh.locate_entities_boundary(mesh, 1, where)
        facets.append(found)
        values.append(np.full(found.size, tag, dtype=np.int32))
    facets, values = np.concatenate(facets), np.concatenate(values)
    order = np.argsort(facets)
    return mesh, dolfinx.mesh.meshtags(mesh, 1, facets[order], values[order])


def by_body(x):
    """The lower block on rank 0, the upper (slave) block on the others (sliced along x)."""
    size = MPI.COMM_WORLD.size
    upper = np.minimum(1 + (x[:, 0] * max(size - 1, 1)).astype(int), size - 1)
    return np.where(x[:, 1] > 0.0, upper, 0)


def cut_along_x(x):
    """Slices along x: every cut crosses the contact zone."""
    size = MPI.COMM_WORLD.size
    return np.minimum((x[:, 0] * size).astype(int), size - 1)


PARTITIONS = {"graph": None, "bodies": by_body, "cut": cut_along_x}


def two_rectangles(
    comm=MPI.COMM_WORLD, *, upper_divisions=4, partition=None, upper_span=(0.0, 1.0), gap=0.0
):
    """The mesh and its facet tags (LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, SYMMETRY).

    ``upper_span``: the x-range of the upper block (the whole lower block's by default); ``gap``:
    the upper block's bottom at y = gap.
    """
    p1, c1 = rectangle_grid((0.0, -0.5), (1.0, 0.5), (4, 2))
    (x0, x1) = upper_span
    p2, c2 = rectangle_grid((x0, gap), (x1 - x0, 0.4), (upper_divisions, 2))
    points, cells = np.vstack([p1, p2]), np.vstack([c1, c2 + p1.shape[0]])
    if comm.rank != 0:
        points, cells = np.empty((0, 2)), np.empty((0, 3), dtype=np.int64)
    owners = None if partition is None else partition(points[cells].mean(axis=1))
    element = compat.coordinate_element("triangle", 1, gdim=2)
    mesh = compat.create_mesh(comm, cells.astype(np.int64), points, element, owners)
    tdim = 2
    mesh.topology.create_connectivity(tdim - 1, tdim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    cell_y = dolfinx.mesh.compute_midpoints(mesh, tdim, np.arange(num_cells, dtype=np.int32))[:, 1]
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    in_upper = cell_y[f_to_c.array[f_to_c.offsets[exterior]]] > 0.0
    x, y = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, exterior)[:, :2].T
    values = np.zeros(exterior.size, dtype=np.int32)
    values[~in_upper & np.isclose(y, -0.5)] = LOWER_BOTTOM
    values[~in_upper & np.isclose(y, 0.0)] = LOWER_TOP
    values[in_upper & np.isclose(y, gap)] = UPPER_BOTTOM
    values[in_upper & np.isclose(y, 0.4 + gap)] = UPPER_TOP
    values[np.isclose(x, 0.0)] = SYMMETRY
    keep = values > 0
    order = np.argsort(exterior[keep])
    return mesh, dolfinx.mesh.meshtags(mesh, tdim - 1, exterior[keep][order], values[keep][order])


def patch_problem(
    comm=MPI.COMM_WORLD,
    *,
    degree=1,
    thickness=1.0,
    upper_divisions=4,
    partition=None,
    rigid=False,
    gap=0.0,
    adjust=None,
):
    """The blocks' contact problem: (problem, pressure Constant, facet tags).

    ``rigid``: the upper block's bottom against the rigid line y = 0 instead of the lower block
    (which then carries nothing). ``gap``: the upper block starts at y = gap; ``adjust``: the
    pair's ADJUST, a distance or a callable giving the NodeSurface from the mesh.
    """
    mesh, ft = two_rectangles(comm, upper_divisions=upper_divisions, partition=partition, gap=gap)
    if callable(adjust):
        adjust = adjust(mesh)
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
    F = thickness * (
        ufl.inner(sigma, ufl.grad(v)) * ufl.dx
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(UPPER_TOP)
    )
    law = ntf.LinearLaw(slope=1e4 * YOUNGS_MODULUS, tension=YOUNGS_MODULUS / 70000)
    master = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0)) if rigid else None
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        master or ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law),
        thickness=thickness,
        adjust=adjust,
    )
    bcs = [component_bc(V, 0, ft.find(SYMMETRY)), component_bc(V, 1, ft.find(LOWER_BOTTOM))]
    return ntf.ContactProblem(F, u, [pair], bcs), pressure, ft


def solve_patch(problem, pressure, value=PRESSURE, increment=0.5):
    """The load ramped to ``value`` in increments of ``increment``; the increments' results."""
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", value * t), initial_increment=increment
    )
    results = step.run(solver, problem.u)
    solver.destroy()
    return results


#: Friction of the drag problem: Coulomb coefficient and stick slope (force/length^3).
MU, STICK_SLOPE = 0.2, 1e3
#: The upper block of the drag problem spans x in DRAG_SPAN: it stays over the lower block, and
#: is wide enough for its trailing edge to stay in contact under MU (no tipping).
DRAG_SPAN = (0.1, 0.9)


def drag_problem(comm=MPI.COMM_WORLD, *, degree=1, partition=None, mu=MU, axisymmetric=False):
    """The upper block pressed onto the lower one, whose top is clamped (a fixed flat line), then
    dragged along x by its top; friction ``mu`` and STICK_SLOPE.

    ``axisymmetric``: the blocks turned by -90 degrees, ``(r, z) = (1 + y, -x)``: a sleeve
    ``1 <= r <= 1.4`` pressed by an external pressure onto a fixed tube ``0.5 <= r <= 1`` and
    dragged along z by its outer surface (a sleeve pulled along a shaft: no hoop strain).

    Returns (problem, pressure Constant, drag Function of the top's tangential displacement,
    facet tags). The upper block has no other support: normally only the contact holds it.
    """
    mesh, ft = two_rectangles(comm, upper_divisions=3, partition=partition, upper_span=DRAG_SPAN)
    if axisymmetric:
        x = mesh.geometry.x
        x[:, 0], x[:, 1] = 1.0 + x[:, 1].copy(), -x[:, 0].copy()
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    if axisymmetric:
        from dolfinx_ntf.fem.axisymmetric import (
            axisymmetric_grad,
            axisymmetric_stress,
            axisymmetric_weight,
        )

        w = axisymmetric_weight(mesh)
        sigma, grad_v = axisymmetric_stress(u, YOUNGS_MODULUS, POISSON_RATIO), axisymmetric_grad(v)
    else:
        w, sigma = 1.0, small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO)
        grad_v = ufl.grad(v)
    F = ufl.inner(sigma, grad_v) * w * ufl.dx
    F += pressure * ufl.inner(ufl.FacetNormal(mesh), v) * w * ds(UPPER_TOP)
    law = ntf.LinearLaw(slope=1e4 * YOUNGS_MODULUS, tension=YOUNGS_MODULUS / 70000)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law, ntf.Friction(mu, STICK_SLOPE)),
        axisymmetric=axisymmetric,
    )
    bcs = [component_bc(V, c, ft.find(LOWER_TOP)) for c in (0, 1)]
    along = 1 if axisymmetric else 0  # the contact line's direction
    Vx, _ = compat.component_space(V, along)
    top = dolfinx.fem.locate_dofs_topological((V.sub(along), Vx), 1, ft.find(UPPER_TOP))
    drag = dolfinx.fem.Function(Vx)
    bcs.append(dolfinx.fem.dirichletbc(drag, top, V.sub(along)))
    return ntf.ContactProblem(F, u, [pair], bcs), pressure, drag, ft


def press_and_drag(problem, pressure, drag, distance, *, increments=2, steps=()):
    """PRESSURE in two increments, then the top dragged by ``distance`` in ``increments``.

    ``steps``: further :class:`~dolfinx_ntf.AnalysisStep` run after the drag (one solver).
    Returns the increments of every step.
    """
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    results = ntf.run_steps(
        solver,
        [
            ntf.AnalysisStep(
                ntf.StaticStep(lambda t: None, initial_increment=0.5, fixed=True),
                loads=[ntf.Load(pressure, PRESSURE)],
                name="press",
            ),
            ntf.AnalysisStep(
                ntf.StaticStep(lambda t: None, initial_increment=1 / increments, fixed=True),
                loads=[ntf.Load(drag, distance)],
                name="drag",
            ),
            *steps,
        ],
    )
    solver.destroy()
    return results
