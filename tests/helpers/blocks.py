"""Two blocks stacked along z, built without gmsh, and the contact problems the tests pose on them.

The lower block is the master body, the upper one (the punch) the slave; facet tags name the
bottom and top of each. ``punch_problem`` presses the punch down, ``drag_problem`` also drags its
top sideways (friction), ``rigid_block`` is a block for contact on a rigid plane,
``block_on_springs`` that block on linear springs.
"""

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress

LOWER, UPPER = 1, 2
LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, UPPER_TOP = 11, 12, 13, 14


def box_grid(origin, size, divisions):
    """Points and hexahedra (dolfinx vertex order) of a box: (origin, size, divisions)."""
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    nx, ny, nz = divisions

    def node(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(), j.ravel(), k.ravel()
    hexes = np.column_stack(
        [
            node(i, j, k),
            node(i + 1, j, k),
            node(i, j + 1, k),
            node(i + 1, j + 1, k),
            node(i, j, k + 1),
            node(i + 1, j, k + 1),
            node(i, j + 1, k + 1),
            node(i + 1, j + 1, k + 1),
        ]
    )
    return points, hexes


def hexes_to_tets(hexes):
    """Six conforming tetrahedra per hexahedron."""
    # Six tetrahedra around the 0-7 diagonal (dolfinx tensor order of hex vertices); conforming
    # across cells.
    paths = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 4, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 6, 7)]
    return np.vstack([hexes[:, p] for p in paths])


def two_blocks(
    comm=MPI.COMM_WORLD,
    *,
    lower=((0, 0, -1), (1, 1, 1), (4, 4, 2)),
    upper=((0, 0, 0), (1, 1, 1), (4, 4, 2)),
    gap=0.0,
    cell="hexahedron",
    partition=None,
):
    """Two boxes (origin, size, divisions) stacked along z; the upper one shifted up by ``gap``.

    ``partition(midpoints)`` optionally gives the process of each cell from its midpoint (MPI
    tests); dolfinx's partitioner decides by default.

    Returns the mesh, cell tags (LOWER, UPPER) and facet tags: LOWER_BOTTOM, LOWER_TOP (master),
    UPPER_BOTTOM (slave), UPPER_TOP.
    """
    (o1, s1, n1), (o2, s2, n2) = lower, upper
    p1, c1 = box_grid(o1, s1, n1)
    o2 = (o2[0], o2[1], o2[2] + gap)
    p2, c2 = box_grid(o2, s2, n2)
    points = np.vstack([p1, p2])
    cells = np.vstack([c1, c2 + p1.shape[0]])
    marker = np.concatenate([np.full(c1.shape[0], LOWER), np.full(c2.shape[0], UPPER)])
    if cell == "tetrahedron":
        cells = hexes_to_tets(cells)
        marker = np.tile(marker, 6)
    if comm.rank != 0:
        points, cells = np.empty((0, 3)), np.empty((0, cells.shape[1]), dtype=np.int64)
    domain = compat.coordinate_element(cell, 1)
    owners = None if partition is None else partition(points[cells].mean(axis=1))
    mesh = compat.create_mesh(comm, cells.astype(np.int64), points, domain, owners)

    tdim = 3
    midpoints = dolfinx.mesh.compute_midpoints(
        mesh, tdim, np.arange(mesh.topology.index_map(tdim).size_local, dtype=np.int32)
    )
    upper_cells = midpoints[:, 2] > o1[2] + s1[2] + 0.5 * gap
    cell_values = np.where(upper_cells, UPPER, LOWER).astype(np.int32)
    cell_tags = dolfinx.mesh.meshtags(
        mesh, tdim, np.arange(cell_values.size, dtype=np.int32), cell_values
    )

    mesh.topology.create_connectivity(tdim - 1, tdim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    z = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, exterior)[:, 2]
    cell_of = f_to_c.array[f_to_c.offsets[exterior]]
    num_local_cells = mesh.topology.index_map(tdim).size_local
    in_upper = np.zeros(exterior.size, dtype=bool)
    owned = cell_of < num_local_cells
    in_upper[owned] = upper_cells[cell_of[owned]]
    bottom1, top1 = o1[2], o1[2] + s1[2]
    bottom2, top2 = o2[2], o2[2] + s2[2]
    values = np.zeros(exterior.size, dtype=np.int32)
    values[~in_upper & np.isclose(z, bottom1)] = LOWER_BOTTOM
    values[~in_upper & np.isclose(z, top1)] = LOWER_TOP
    values[in_upper & np.isclose(z, bottom2)] = UPPER_BOTTOM
    values[in_upper & np.isclose(z, top2)] = UPPER_TOP
    keep = values > 0
    order = np.argsort(exterior[keep])
    facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, exterior[keep][order], values[keep][order])
    return mesh, cell_tags, facet_tags


YOUNGS_MODULUS, POISSON_RATIO = 1000.0, 0.3
PUNCH = ((0.2, 0.2, 0.0), (0.6, 0.6, 0.5), (3, 3, 2))


def elastic_residual(u, v, facet_tags, pressure, youngs_modulus=YOUNGS_MODULUS):
    """Small-strain elasticity with ``pressure`` on the upper block's top."""
    mesh = u.function_space.mesh
    sigma = small_strain_stress(u, youngs_modulus, POISSON_RATIO)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    return ufl.inner(sigma, ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)


def displacement_fields(mesh, degree=1):
    """The displacement space, the unknown, the test function and a pressure Constant (0)."""
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    return V, u, v, pressure


def punch_conditions(V, facet_tags, top=None):
    """The lower block clamped at its bottom; the punch top (or the facets ``top``) moves
    vertically only."""
    ft = facet_tags
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    top = ft.find(UPPER_TOP) if top is None else top
    return [
        dolfinx.fem.dirichletbc(np.zeros(3), bottom, V),
        component_bc(V, 0, top),
        component_bc(V, 1, top),
    ]


def drag_conditions(V, facet_tags):
    """The lower block clamped at its bottom; the punch top's x and y displacements prescribed.

    Returns the Dirichlet conditions and the two Functions (x, y) that prescribe the drag.
    """
    ft = facet_tags
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), bottom, V)]
    drag = []
    for component in (0, 1):
        Vc, _ = compat.component_space(V, component)
        dofs = dolfinx.fem.locate_dofs_topological((V.sub(component), Vc), 2, ft.find(UPPER_TOP))
        g = dolfinx.fem.Function(Vc)
        bcs.append(dolfinx.fem.dirichletbc(g, dofs, V.sub(component)))
        drag.append(g)
    return bcs, drag


def punch_bulk(mesh, facet_tags, top=None):
    """Elasticity with a pressure on the punch top under ``punch_conditions``: what a test adds its
    contact pairs to.

    Returns:
        The displacement, the residual, the pressure Constant (0 until set) and the conditions.
    """
    V, u, v, pressure = displacement_fields(mesh)
    bcs = punch_conditions(V, facet_tags, top)
    return u, elastic_residual(u, v, facet_tags, pressure), pressure, bcs


def punch_problem(
    cell="hexahedron",
    upper=PUNCH,
    *,
    degree=1,
    rollers=False,
    law=None,
    friction=None,
    gap=0.0,
    name="",
    comm=MPI.COMM_WORLD,
    partition=None,
    **problem_options,
):
    """Upper block (the punch, slave) pressed by a pressure on its top onto a lower block (master).

    The lower block is clamped at its bottom and the punch top moves vertically only; ``rollers``
    puts both bodies on symmetry planes and the bottom on rollers instead (uniform stress exact).

    Returns:
        The problem, the pressure Constant (0 until set) and the facet tags.
    """
    mesh, _, ft = two_blocks(comm, cell=cell, upper=upper, gap=gap, partition=partition)
    V, u, v, pressure = displacement_fields(mesh, degree)
    F = elastic_residual(u, v, ft, pressure)
    if rollers:
        x0 = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 0.0))
        y0 = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[1], 0.0))
        bcs = [
            component_bc(V, 0, x0),
            component_bc(V, 1, y0),
            component_bc(V, 2, ft.find(LOWER_BOTTOM)),
        ]
    else:
        bcs = punch_conditions(V, ft)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law or ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS), friction),
        name=name,
    )
    return ntf.ContactProblem(F, u, [pair], bcs, **problem_options), pressure, ft


BLOCK_CONTACT, BLOCK_TOP = 1, 2


def rigid_block(cell_type="tetrahedron", height=0.5, divisions=(3, 4, 2), degree=1):
    """A block [0,1]x[0,1]x[0,height] on rollers (x = 0, y = 0), for contact on a rigid plane z = 0.

    Returns the displacement space, the facet tags (BLOCK_CONTACT bottom, BLOCK_TOP top) and the
    Dirichlet conditions: rollers and the top's u_z (zero until set through its Function).
    """
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD,
        [[0, 0, 0], [1, 1, height]],
        list(divisions),
        getattr(dolfinx.mesh.CellType, cell_type),
    )
    V = compat.vector_space(mesh, "Lagrange", degree)

    def facets(where):
        return dolfinx.mesh.locate_entities_boundary(mesh, 2, where)

    bottom, top = (
        facets(lambda x: np.isclose(x[2], 0.0)),
        facets(lambda x: np.isclose(x[2], height)),
    )
    entities = np.concatenate([bottom, top])
    values = np.concatenate([np.full(bottom.size, BLOCK_CONTACT), np.full(top.size, BLOCK_TOP)])
    order = np.argsort(entities)
    tags = dolfinx.mesh.meshtags(mesh, 2, entities[order], values[order].astype(np.int32))
    bcs = [
        component_bc(V, 0, facets(lambda x: np.isclose(x[0], 0.0))),
        component_bc(V, 1, facets(lambda x: np.isclose(x[1], 0.0))),
        component_bc(V, 2, top),
    ]
    return V, tags, bcs


def block_on_springs(height: float, E: float, K: float, divisions=(1, 1, 2), **options):
    """The ``rigid_block`` (hexahedra) on rollers only, on LINEAR springs (slope ``K``) onto the
    plane z = 0, its top loaded by a pressure (a Constant, zero until set).

    Returns the problem (``options`` go to ``ContactProblem``), the pressure and the law.
    """
    V, tags, bcs = rigid_block("hexahedron", height, divisions)
    mesh = V.mesh
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    F = ufl.inner(small_strain_stress(u, E, 0.0), ufl.grad(v)) * ufl.dx
    F += pressure * v[2] * ds(BLOCK_TOP)
    law = ntf.LinearLaw(slope=K, tension=1e-6 * K)
    pair = ntf.ContactPair(
        ntf.FacetSurface(tags, BLOCK_CONTACT),
        ntf.RigidPlane((0, 0, 0), (0, 0, 1)),
        ntf.SurfaceInteraction(law),
    )
    return ntf.ContactProblem(F, u, [pair], bcs[:2], **options), pressure, law


MU, STICK_SLOPE, PRESSURE = 0.2, 500.0, 10.0


def drag_problem(mu=MU, stick_slope=STICK_SLOPE, gap=0.0, **options):
    """The punch of ``punch_problem``, its top moved horizontally by ``drag`` (a Function's value).

    Returns the problem, the pressure Constant, the drag value setter and the facet tags; the
    Function of the prescribed x displacement of the top is ``problem.drag``.
    """
    mesh, _, ft = two_blocks(MPI.COMM_WORLD, upper=PUNCH, gap=gap)
    V, u, v, pressure = displacement_fields(mesh)
    F = elastic_residual(u, v, ft, pressure)
    bcs, drag = drag_conditions(V, ft)

    def set_drag(value):
        drag[0].x.array[:] = value

    law = ntf.LinearLaw.with_ccx_defaults(1000.0)
    interaction = ntf.SurfaceInteraction(law, ntf.Friction(mu, stick_slope))
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), interaction
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs, **options)
    problem.drag = drag[0]
    return problem, pressure, set_drag, ft


def solve_increments(problem, pressure, load=10.0, increments=2):
    """``load`` on the punch in ``increments`` fixed increments: the solver and the results."""
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", load * t),
        initial_increment=1.0 / increments,
        fixed=True,
    )
    results = step.run(solver, problem.u)
    return solver, results
