"""gmsh meshes of prisms (alone or beside hexahedra) read as collapsed hexahedra, with contact.

docs/method.md §32. The geometry (``helpers.prism_blocks``): a punch on a base, each a box made by
extruding a square, as prisms (a triangulated square) or hexahedra. Runs in serial and under
``mpirun -n 2`` (every compared quantity is reduced over the communicator); the finite-difference
check of the tangent is serial.
"""

from itertools import combinations

from mpi4py import MPI

import gmsh
import numpy as np
import pytest
from helpers import (
    LOWER_BOTTOM,
    LOWER_TOP,
    UPPER_BOTTOM,
    UPPER_TOP,
    YOUNGS_MODULUS,
    displacement_fields,
    elastic_residual,
    punch_conditions,
    solve_increments,
)
from helpers.jacobian_check import directional_derivative
from helpers.prism_blocks import BASE, PUNCH, build_prism_on_hex

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf.fem.elasticity import component_bc
from dolfinx_ntf.kernels.collapsed_wedges import collapse_wedges, wedge_rotations
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

COMM = MPI.COMM_WORLD
#: The punch as wide as the base: a uniform pressure goes through unchanged (patch test).
FULL = ((0.0, 0.0, 0.0), (1.0, 1.0, 0.5), (4, 4, 2))
CELLS = [("prism", "hexahedron"), ("hexahedron", "prism"), ("prism", "prism")]


def _total(form) -> float:
    """A scalar form assembled over all processes."""
    return COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(form)), op=MPI.SUM)


@pytest.mark.mpi
@pytest.mark.parametrize("structured", [False, True])
@pytest.mark.parametrize(("punch_cell", "base_cell"), CELLS)
def test_prism_meshes_have_their_volumes_and_tagged_areas(punch_cell, base_cell, structured):
    mesh, cell_tags, facet_tags = mesh_from_gmsh(
        build_prism_on_hex, COMM, punch_cell=punch_cell, base_cell=base_cell, structured=structured
    )
    assert mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    assert _total(1.0 * dx(BASE)) == pytest.approx(1.0, rel=1e-12)
    assert _total(1.0 * dx(PUNCH)) == pytest.approx(0.18, rel=1e-12)
    # the prisms' triangles (bottom and top) and the hexahedra's quadrilaterals, tagged
    for tag, area in (
        (LOWER_BOTTOM, 1.0),
        (LOWER_TOP, 1.0),
        (UPPER_BOTTOM, 0.36),
        (UPPER_TOP, 0.36),
    ):
        assert _total(1.0 * ds(tag)) == pytest.approx(area, rel=1e-12), tag
    # outward normals of the triangles: the punch bottom looks down, its top up
    n = ufl.FacetNormal(mesh)
    assert _total(n[2] * ds(UPPER_BOTTOM)) == pytest.approx(-0.36, rel=1e-12)
    assert _total(n[2] * ds(UPPER_TOP)) == pytest.approx(0.36, rel=1e-12)
    # the whole boundary: the collapsed faces (edges) add nothing, no inner facet counts
    assert _total(1.0 * ds) == pytest.approx(6.0 + 2 * 0.36 + 4 * 0.6 * 0.5, rel=1e-12)


def _one_prism(x: list[float], order: list[int]) -> None:
    """One prism of nodes ``x`` (6 x 3, flat) in the node ``order`` (discrete entities)."""
    gmsh.model.add("one_prism")
    volume = gmsh.model.addDiscreteEntity(3)
    gmsh.model.mesh.addNodes(3, volume, [1, 2, 3, 4, 5, 6], x)
    gmsh.model.mesh.addElementsByType(volume, 6, [7], order)
    gmsh.model.addPhysicalGroup(3, [volume], 1)


UNIT_PRISM = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1]


@pytest.mark.mpi
def test_a_prism_numbered_clockwise_is_read_mirrored():
    """gmsh's own meshes are counter-clockwise; a written file may not be."""
    mesh, _, _ = mesh_from_gmsh(_one_prism, COMM, x=UNIT_PRISM, order=[1, 3, 2, 4, 6, 5])
    assert _total(1.0 * ufl.dx(domain=mesh)) == pytest.approx(0.5, rel=1e-12)
    x = ufl.SpatialCoordinate(mesh)
    assert _total(x[0] * ufl.dx(domain=mesh)) == pytest.approx(0.5 / 3, rel=1e-12)


@pytest.mark.mpi
def test_second_order_prisms_are_refused():
    with pytest.raises(ValueError, match="second-order prisms are read alone"):
        mesh_from_gmsh(build_prism_on_hex, COMM, order=2)


@pytest.mark.mpi
def test_a_flat_prism_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"prism 7 .*flat or inverted"):
        flat = [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0.2, 1, 0]  # top on the bottom
        mesh_from_gmsh(_one_prism, COMM, x=flat, order=[1, 2, 3, 4, 5, 6])


def _overlapping_prisms() -> None:
    """A prism on each of the 20 triangles of a hexagon's 6 corners (counter-clockwise)."""
    gmsh.model.add("overlapping")
    volume = gmsh.model.addDiscreteEntity(3)
    angles = np.arange(6) * np.pi / 3
    plane = np.column_stack([np.cos(angles), np.sin(angles)])
    x = np.vstack([np.column_stack([plane, np.full(6, z)]) for z in (0.0, 1.0)])
    gmsh.model.mesh.addNodes(3, volume, list(range(1, 13)), x.ravel().tolist())
    rows = [[*t, *(np.array(t) + 6)] for t in combinations(range(6), 3)]  # increasing: CCW
    tags = list(range(101, 101 + len(rows)))
    gmsh.model.mesh.addElementsByType(volume, 6, tags, (np.array(rows) + 1).ravel().tolist())
    gmsh.model.addPhysicalGroup(3, [volume], 1)


@pytest.mark.mpi
def test_prisms_whose_edges_cannot_be_collapsed_are_refused_naming_one():
    """20 stacks on 6 vertical lines: no rotation keeps a collapsed edge to two cells (§32.2)."""
    with pytest.raises(ValueError, match=r"prism 1\d\d: no numbering .* at most two wedges"):
        mesh_from_gmsh(_overlapping_prisms, COMM)


def _extruded_prisms(size: float, layers: int) -> np.ndarray:
    """``(e, 6)`` 0-based prisms of gmsh's extrusion of a Delaunay-meshed 2 x 1 rectangle."""
    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("extruded")
        square = gmsh.model.occ.addRectangle(0.0, 0.0, 0.0, 2.0, 1.0)
        gmsh.model.occ.extrude([(2, square)], 0, 0, 0.5, numElements=[layers], recombine=True)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.setSize(gmsh.model.getEntities(0), size)
        gmsh.model.mesh.generate(3)
        types, _, nodes = gmsh.model.mesh.getElements(3)
        return np.asarray(nodes[list(types).index(6)], dtype=np.int64).reshape(-1, 6) - 1
    finally:
        gmsh.finalize()


@pytest.mark.serial
@pytest.mark.parametrize("layers", [1, 3])
def test_rotations_of_a_larger_extrusion_obey_the_shared_rule(layers):
    """Thousands of prisms (one layer: twice as many stacks as vertical lines, the tight case):
    stacked prisms repeat a corner on their shared triangle, a collapsed edge belongs to at most
    two prisms, and two only if they share no face (§32.2)."""
    rows = _extruded_prisms(0.04, layers)
    assert rows.shape[0] > 2500 * layers
    hexahedra = collapse_wedges(rows, wedge_rotations(rows, shared=True))
    faces = np.sort(np.vstack([hexahedra[:, :4], hexahedra[:, 4:]]), axis=1)
    triangles = np.sort(np.vstack([rows[:, :3], rows[:, 3:]]), axis=1)
    _, face_counts = np.unique(faces, axis=0, return_counts=True)
    _, triangle_counts = np.unique(triangles, axis=0, return_counts=True)
    assert np.sum(triangle_counts == 2) == (layers - 1) * rows.shape[0] // layers  # inner planes
    assert np.sum(face_counts == 2) == np.sum(triangle_counts == 2)
    edges = np.sort(hexahedra[:, [2, 6]], axis=1)
    _, users, counts = np.unique(edges, axis=0, return_inverse=True, return_counts=True)
    users = users.ravel()
    assert counts.max() <= 2
    order = np.argsort(users, kind="stable")
    pairs = order[counts[users[order]] == 2].reshape(-1, 2)
    assert np.all(users[pairs[:, 0]] == users[pairs[:, 1]])
    common = (rows[pairs[:, 0], :, None] == rows[pairs[:, 1], None, :]).any(axis=2).sum(axis=1)
    assert np.all(common == 2)  # the collapsed edge only, no face
    if layers == 1:
        assert pairs.shape[0] > 0.4 * rows.shape[0]  # the tight case: most edges are shared


def _patch_problem(punch_cell: str, base_cell: str):
    """The punch as wide as the base, on rollers, pressed by a pressure on its top."""
    mesh, _, ft = mesh_from_gmsh(
        build_prism_on_hex,
        COMM,
        punch=FULL,
        punch_cell=punch_cell,
        base_cell=base_cell,
        structured=True,
    )
    V, u, v, pressure = displacement_fields(mesh)
    F = elastic_residual(u, v, ft, pressure)

    def plane(axis):
        return dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[axis], 0.0))

    bcs = [component_bc(V, 0, plane(0)), component_bc(V, 1, plane(1))]
    bcs.append(component_bc(V, 2, ft.find(LOWER_BOTTOM)))
    law = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law),
    )
    return ntf.ContactProblem(F, u, [pair], bcs), pressure, ft, law


@pytest.mark.mpi
def test_patch_test_on_prism_blocks_transmits_the_pressure_exactly():
    """Triangles of prisms as slave and as master faces (matching grids cut alike)."""
    problem, pressure, _, _ = _patch_problem("prism", "prism")
    solve_increments(problem, pressure, load=10.0)
    res = ntf.contact_results(problem)[0]
    assert COMM.allreduce(res.node.size, op=MPI.SUM) == 25
    gathered = np.concatenate(COMM.allgather(res.pressure))
    np.testing.assert_allclose(gathered, gathered.mean(), rtol=1e-8)
    assert COMM.allreduce(np.sum(res.pressure * res.area), op=MPI.SUM) == pytest.approx(
        10.0, rel=1e-10
    )


@pytest.mark.mpi
def test_prism_blocks_deform_as_hexahedral_blocks_under_uniform_pressure():
    """The uniform state is in both spaces: the same top displacement, and the closed form."""
    top, clearance = {}, {}
    for cells in (("prism", "prism"), ("hexahedron", "hexahedron")):
        problem, pressure, ft, _ = _patch_problem(*cells)
        solve_increments(problem, pressure, load=10.0)
        ds = ufl.Measure("ds", domain=problem.u.function_space.mesh, subdomain_data=ft)
        top[cells] = _total(problem.u[2] * ds(UPPER_TOP))  # area 1: the mean
        assert ntf.contact_force(problem)[2] == pytest.approx(10.0, rel=1e-10)
        res = ntf.contact_results(problem)[0]
        gathered = np.concatenate(COMM.allgather(res.clearance))
        np.testing.assert_allclose(gathered, gathered.mean(), rtol=1e-8)
        clearance[cells] = gathered.mean()
    prisms, hexahedra = ("prism", "prism"), ("hexahedron", "hexahedron")
    assert top[prisms] == pytest.approx(top[hexahedra], rel=1e-10)
    assert clearance[prisms] == pytest.approx(clearance[hexahedra], rel=1e-10)
    # both blocks compressed by p/E over their heights (1 + 0.5), plus the springs' overclosure
    closed = -10.0 * 1.5 / YOUNGS_MODULUS + clearance[prisms]
    assert top[prisms] == pytest.approx(closed, rel=1e-10)


@pytest.mark.mpi
@pytest.mark.parametrize(
    ("punch_cell", "base_cell"), [("prism", "hexahedron"), ("hexahedron", "prism")]
)
def test_triangles_against_quadrilaterals_with_coincident_nodes(punch_cell, base_cell):
    """Slave nodes on the master's nodes, among them the repeated corners of master triangles
    (§32.3: it stopped with "singular projection" before the polished projection). Not a patch
    test: the triangles' and quadrilaterals' corner shares differ (measured spread 0.35, 0.22)."""
    problem, pressure, _, _ = _patch_problem(punch_cell, base_cell)
    solve_increments(problem, pressure, load=10.0)
    res = ntf.contact_results(problem)[0]
    assert COMM.allreduce(res.node.size, op=MPI.SUM) == 25
    assert ntf.contact_force(problem)[2] == pytest.approx(10.0, rel=1e-10)
    assert COMM.allreduce(int(np.sum(res.clearance >= 0)), op=MPI.SUM) == 0


def _punch_problem(punch_cell: str, base_cell: str, structured: bool = False):
    """The small punch (0.6 x 0.6) on the base: non-matching surfaces."""
    mesh, _, ft = mesh_from_gmsh(
        build_prism_on_hex, COMM, punch_cell=punch_cell, base_cell=base_cell, structured=structured
    )
    V, u, v, pressure = displacement_fields(mesh)
    F = elastic_residual(u, v, ft, pressure)
    law = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law),
    )
    return ntf.ContactProblem(F, u, [pair], punch_conditions(V, ft)), pressure


@pytest.mark.mpi
@pytest.mark.parametrize(("punch_cell", "base_cell"), CELLS)
def test_triangles_of_prisms_as_slave_and_master_faces_carry_the_load(punch_cell, base_cell):
    problem, pressure = _punch_problem(punch_cell, base_cell)
    solve_increments(problem, pressure, load=10.0)
    res = ntf.contact_results(problem)[0]
    vertical = COMM.allreduce(res.force[:, 2].sum(), op=MPI.SUM)
    assert vertical == pytest.approx(10.0 * 0.36, rel=1e-10)
    assert COMM.allreduce(res.node.size, op=MPI.SUM) > 0
    assert COMM.allreduce(int(np.sum(res.clearance >= 0)), op=MPI.SUM) == 0
    carried = COMM.allreduce(np.sum(res.pressure * res.area), op=MPI.SUM)
    assert carried == pytest.approx(3.6, rel=1e-4)  # normals tilted by the base's bending


@pytest.mark.serial
@pytest.mark.parametrize(("punch_cell", "base_cell"), CELLS)
def test_spring_tangent_on_prism_faces_matches_finite_differences(punch_cell, base_cell):
    problem, pressure = _punch_problem(punch_cell, base_cell)
    solve_increments(problem, pressure, load=10.0)
    check = directional_derivative(problem, amplitude=1e-3, h=1e-4, seed=1)
    assert check.contact_scale > 0
    np.testing.assert_allclose(check.product, check.difference, atol=1e-6 * check.contact_scale)
