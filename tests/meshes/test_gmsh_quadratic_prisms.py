"""gmsh's 15- and 18-node prisms read as 18-node prism meshes on dolfinx 0.11 (docs/method.md §40).

The block and the quarter annulus of ``helpers.quadratic_prisms``: node order against basix's
degree-2 prism, volumes, faces and their pressure forces, a patch test, and the block against
ccx 2.20 (the same mesh written as a C3D15 deck). Older releases refuse the model. The reading,
volume, face and patch tests also run under ``mpirun -n 2`` (every compared quantity reduced).
"""

from __future__ import annotations

import shutil

from mpi4py import MPI

import gmsh
import numpy as np
import pytest
from helpers.quadratic_prisms import (
    BOTTOM,
    END,
    POISSON,
    START,
    TOP,
    VOLUME,
    YOUNGS_MODULUS,
    build_prism_block,
    build_prism_sector,
    clamped_dofs,
    solve_wedge15,
)

import basix
import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.elements import ELEMENT_TYPES
from dolfinx_ntf.calculix.model.c3d15 import c3d15_metadata
from dolfinx_ntf.fem.serendipity_wedge import wedge15_metadata, wedge15_space
from dolfinx_ntf.fem.wedge_faces import WEDGE_FACES, PrismFaces, prism_face_forces
from dolfinx_ntf.meshes.gmsh_io import _MIRROR, mesh_from_gmsh

COMM = MPI.COMM_WORLD
ON_011 = compat.DOLFINX_VERSION >= (0, 11)
needs_011 = pytest.mark.skipif(not ON_011, reason="degree-2 prisms need dolfinx 0.11 (§32.5)")
KINDS = pytest.mark.parametrize("incomplete", [True, False], ids=["15-node", "18-node"])


def _total(value) -> np.ndarray:
    return COMM.allreduce(np.asarray(value, dtype=float), op=MPI.SUM)


def _owned_cells(mesh) -> int:
    return mesh.topology.index_map(3).size_local


def test_faces_are_ccx_c3d15_faces():
    """WEDGE_FACES are ccx's C3D15 faces S1..S5 in basix's numbering, quadrilateral centres last."""
    etype = ELEMENT_TYPES["C3D15"]
    slot_of_ccx = np.argsort(etype.to_dolfinx)  # ccx node (0-based) -> basix slot
    centres = {(0, 1, 3, 4): 15, (0, 2, 3, 5): 16, (1, 2, 4, 5): 17}
    for k, face in enumerate(etype.faces):
        size = 6 if k < 2 else 8
        expected = [int(slot_of_ccx[n]) for n in face[:size]]  # 0-based
        if size == 8:
            expected.append(centres[tuple(sorted(expected[:4]))])
        assert list(WEDGE_FACES[k]) == expected


def test_rule_is_the_deck_runners():
    """The public 9-point rule is the deck runner's C3D15 rule."""
    assert wedge15_metadata() == c3d15_metadata()


def test_mirror_is_the_same_prism():
    """_MIRROR swaps basix's vertices 1, 2 and 4, 5 and maps every edge and face onto its image."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    points = element.points
    swapped = points[:, [1, 0, 2]]  # the reflection x <-> y of the reference prism
    np.testing.assert_allclose(points[_MIRROR], swapped, atol=1e-15)


@pytest.mark.mpi
@pytest.mark.skipif(ON_011, reason="dolfinx 0.11 reads second-order prisms")
@KINDS
def test_refused_before_011(incomplete):
    with pytest.raises(NotImplementedError, match=r"dolfinx 0\.11 or later.*dolfinx 0\.\d+ cannot"):
        mesh_from_gmsh(build_prism_block, COMM, incomplete=incomplete)


@pytest.mark.mpi
@needs_011
@KINDS
def test_node_order_and_tags(incomplete):
    """Every cell's geometry nodes sit at basix's degree-2 points of its straight prism."""
    mesh, cell_tags, faces = mesh_from_gmsh(build_prism_block, COMM, incomplete=incomplete)
    assert isinstance(faces, PrismFaces)
    assert mesh.topology.cell_type.name == "prism"
    x = mesh.geometry.x[compat.geometry_dofs(mesh)]  # (C, 18, 3)
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    linear = basix.create_element(basix.ElementFamily.P, basix.CellType.prism, 1)
    phi = linear.tabulate(0, element.points)[0, :, :, 0]  # (18, 6)
    np.testing.assert_allclose(x, np.einsum("nk,ckd->cnd", phi, x[:, :6]), atol=1e-13)
    n = _owned_cells(mesh)
    assert np.all(cell_tags.values[np.isin(cell_tags.indices, np.arange(n))] == VOLUME)
    assert _total(np.count_nonzero(cell_tags.indices < n)) == _total(n) > 0
    assert set(faces.values.tolist()) == {BOTTOM, TOP, END, START}
    assert faces.quadrilaterals.shape[1] == 9 and faces.triangles.shape[1] == 6


def _volume(mesh, metadata=None) -> float:
    dx = ufl.Measure("dx", domain=mesh, metadata=metadata or {})
    one = dolfinx.fem.Constant(mesh, 1.0)
    return COMM.allreduce(dolfinx.fem.assemble_scalar(dolfinx.fem.form(one * dx)), op=MPI.SUM)


@pytest.mark.mpi
@needs_011
@KINDS
def test_volumes(incomplete):
    """The block's volume exactly; the quarter annulus's (curved arcs) close to pi 3/4."""
    mesh, _, _ = mesh_from_gmsh(build_prism_block, COMM, incomplete=incomplete)
    assert _volume(mesh) == pytest.approx(2.0, rel=1e-13)
    assert _volume(mesh, wedge15_metadata()) == pytest.approx(2.0, rel=1e-13)
    mesh, _, _ = mesh_from_gmsh(build_prism_sector, COMM, incomplete=incomplete)
    exact = np.pi * 3.0 / 4.0
    error = abs(_volume(mesh, wedge15_metadata()) - exact) / exact
    assert error < 1e-5  # 2.1e-6; the same corners as collapsed hexahedra: 7.3e-4 (§40.4)


@pytest.mark.mpi
@needs_011
@KINDS
def test_pressure_forces_are_outward(incomplete):
    """A unit pressure's forces sum to -area x outward normal on each tagged face."""
    mesh, _, faces = mesh_from_gmsh(build_prism_sector, COMM, incomplete=incomplete)
    V, _ = wedge15_space(mesh)
    owned = V.dofmap.index_map.size_local
    expected = {
        TOP: [0, 0, -np.pi * 3 / 4],
        BOTTOM: [0, 0, np.pi * 3 / 4],
        END: [0, 1, 0],  # y = 0, area 1, outward -y
        START: [1, 0, 0],
    }
    for tag, total in expected.items():
        f = prism_face_forces(V, faces, tag, 1.0).x.array.reshape(-1, 3)[:owned]
        np.testing.assert_allclose(_total(f.sum(axis=0)), total, atol=2e-4)
    with pytest.raises(ValueError, match="no face has tag 99"):
        prism_face_forces(V, faces, 99, 1.0)


@pytest.mark.mpi
@needs_011
@KINDS
def test_patch_uniform_compression(incomplete):
    """Pressure p on top, rollers on x = 0, y = 0, z = 0: u = (nu x, nu y, -z) p / E exactly."""
    mesh, _, faces = mesh_from_gmsh(build_prism_block, COMM, incomplete=incomplete)
    V, constraints = wedge15_space(mesh)
    bcs = []
    for component in range(3):
        dofs = clamped_dofs(V, lambda x, c=component: np.isclose(x[c], 0.0), constraints, component)
        bcs.append(dolfinx.fem.dirichletbc(0.0, dofs, V.sub(component)))
    p = 10.0
    u = solve_wedge15(V, constraints, bcs, prism_face_forces(V, faces, TOP, p))
    x = V.tabulate_dof_coordinates()
    exact = np.column_stack([POISSON * x[:, 0], POISSON * x[:, 1], -x[:, 2]]) * p / YOUNGS_MODULUS
    error = np.abs(u.x.array.reshape(-1, 3) - exact).max(initial=0.0)
    assert COMM.allreduce(error, op=MPI.MAX) < 1e-12 * p / YOUNGS_MODULUS  # 2.7e-14 measured


def _one_prism(x: np.ndarray, order: np.ndarray, triangle: list[int] | None = None) -> None:
    """One second-order prism (element 7) of nodes ``x`` (basix order) in the node ``order``.

    ``triangle``: six nodes (basix slots) of a tagged 6-node triangle (element 8), group 11.
    """
    gmsh.model.add("one_quadratic_prism")
    volume = gmsh.model.addDiscreteEntity(3)
    n = order.size
    gmsh.model.mesh.addNodes(3, volume, list(range(1, n + 1)), x[:n].ravel().tolist())
    gmsh.model.mesh.addElementsByType(volume, 13 if n == 18 else 18, [7], (order + 1).tolist())
    gmsh.model.addPhysicalGroup(3, [volume], 1)
    if triangle is not None:
        surface = gmsh.model.addDiscreteEntity(2)
        gmsh.model.mesh.addElementsByType(surface, 9, [8], [t + 1 for t in triangle])
        gmsh.model.addPhysicalGroup(2, [surface], 11)


def _unit_prism() -> np.ndarray:
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    return np.array(element.points)  # a copy: basix returns a read-only array


@pytest.mark.mpi
@needs_011
@pytest.mark.parametrize("n", [15, 18])
def test_a_prism_numbered_clockwise_is_read_mirrored(n):
    """A written file may number the triangle clockwise: the prism is mirrored, the same."""
    x = _unit_prism()
    mesh, _, _ = mesh_from_gmsh(_one_prism, COMM, x=x, order=_MIRROR[:n])
    assert _volume(mesh, wedge15_metadata()) == pytest.approx(0.5, rel=1e-13)
    coordinate = ufl.SpatialCoordinate(mesh)
    first = dolfinx.fem.form(coordinate[0] * ufl.dx(domain=mesh))
    assert COMM.allreduce(dolfinx.fem.assemble_scalar(first)) == pytest.approx(1 / 6, rel=1e-13)


@pytest.mark.mpi
@needs_011
@pytest.mark.parametrize("n", [15, 18])
def test_a_folded_prism_is_refused_naming_it(n):
    x = _unit_prism()
    x[6] = [0.7, 0.9, 0.0]  # the midside node of 0-1 moved past vertex 2: folded
    with pytest.raises(ValueError, match=r"prism 7 .*Jacobian <= 0"):
        mesh_from_gmsh(_one_prism, COMM, x=x, order=np.arange(n))


def _deck(mesh, faces: PrismFaces, pressures: dict[int, float]) -> tuple[str, np.ndarray]:
    """The serial mesh as a C3D15 deck: clamped at x = 0, ``*DLOAD`` on the tagged faces."""
    cells = np.asarray(mesh.geometry.input_global_indices)[compat.geometry_dofs(mesh)]
    ccx_cells = cells[:, np.argsort(ELEMENT_TYPES["C3D15"].to_dolfinx)] + 1
    used = np.unique(ccx_cells)
    inputs = np.asarray(mesh.geometry.input_global_indices)
    coords = np.zeros((inputs.max() + 2, 3))
    coords[inputs + 1] = mesh.geometry.x
    lines = ["*NODE, NSET=NALL"]
    lines += [f"{n}, {coords[n, 0]:.17g}, {coords[n, 1]:.17g}, {coords[n, 2]:.17g}" for n in used]
    lines.append("*ELEMENT, TYPE=C3D15, ELSET=EALL")
    lines += [
        f"{e + 1}, " + ", ".join(map(str, row[:8])) + ",\n" + ", ".join(map(str, row[8:]))
        for e, row in enumerate(ccx_cells)
    ]
    start = used[np.isclose(coords[used, 0], 0.0)]
    lines.append("*NSET, NSET=START")
    lines += [f"{n}," for n in start]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{YOUNGS_MODULUS}, {POISSON}"]
    lines += ["*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL", "*STEP", "*STATIC"]
    lines += ["*BOUNDARY", "START, 1, 3", "*DLOAD"]
    keys = {}
    for e, row in enumerate(cells):
        for k, face in enumerate(WEDGE_FACES):
            keys[tuple(sorted(row[list(face[: 3 if k < 2 else 4])]))] = (e + 1, k + 1)
    for tag, value in pressures.items():
        triangles, quads = faces.find(tag)
        for face in [*triangles[:, :3], *quads[:, :4]]:
            element, k = keys[tuple(sorted(face))]
            lines.append(f"{element}, P{k}, {value!r}")
    lines += ["*NODE PRINT, NSET=NALL", "U", "*END STEP", ""]
    return "\n".join(lines), used


@needs_011
@pytest.mark.skipif(shutil.which("ccx") is None, reason="needs ccx 2.20")
@KINDS
def test_bending_against_ccx(incomplete, tmp_path):
    """Clamped at x = 0, pressures 10 on top and 40 at x = 2: U equals ccx's printed digits.

    The same mesh written as a C3D15 deck (gmsh's nodes, ccx's node order, ``*DLOAD`` on the
    elements' faces) and run by ccx 2.20: all 901 nodes' U, rounded as ccx prints them.
    """
    from dolfinx_ntf.calculix.ccx import dat_block, read_ccx_dat, run_ccx
    from dolfinx_ntf.calculix.dat import format_e13

    if COMM.size > 1:
        pytest.skip("the deck is written from the serial mesh")
    mesh, _, faces = mesh_from_gmsh(build_prism_block, COMM, incomplete=incomplete, size=0.4)
    V, constraints = wedge15_space(mesh)
    dofs = clamped_dofs(V, lambda x: np.isclose(x[0], 0.0), constraints)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), dofs, V)]
    pressures = {TOP: 10.0, END: 40.0}
    forces = prism_face_forces(V, faces, TOP, pressures[TOP])
    forces.x.array[:] += prism_face_forces(V, faces, END, pressures[END]).x.array
    u = solve_wedge15(V, constraints, bcs, forces)
    deck, used = _deck(mesh, faces, pressures)
    (tmp_path / "prisms.inp").write_text(deck)
    run_ccx(tmp_path, "prisms", timeout=120)
    block = dat_block(read_ccx_dat(tmp_path, "prisms"), "U")
    # our displacement at each ccx node: geometry node of that input index -> dof
    dof_of_node = np.full(mesh.geometry.x.shape[0], -1)
    dof_of_node[compat.geometry_dofs(mesh).ravel()] = compat.cell_dofs(V).ravel()
    row = np.full(np.max(mesh.geometry.input_global_indices) + 2, -1)
    row[np.asarray(mesh.geometry.input_global_indices) + 1] = dof_of_node
    ours = u.x.array.reshape(-1, 3)[row[block.labels]]
    assert np.abs(block.values).max() > 1e-4  # bent, not a trivial answer
    assert np.array_equal(np.sort(block.labels), used)
    printed = np.vectorize(lambda value: float(format_e13(value)))(ours)  # ccx's 1PE13.6
    np.testing.assert_array_equal(printed, block.values)


@pytest.mark.mpi
@needs_011
def test_a_tagged_face_of_no_prism_is_refused_naming_it():
    x = _unit_prism()
    with pytest.raises(ValueError, match=r"element 8 of physical group 11 is no face of a prism"):
        mesh_from_gmsh(_one_prism, COMM, x=x, order=np.arange(15), triangle=[0, 1, 3, 6, 10, 8])
    # the bottom triangle, numbered inward as gmsh may: read outward (S1 of ccx's C3D15)
    _, _, faces = mesh_from_gmsh(
        _one_prism, COMM, x=x, order=np.arange(15), triangle=[0, 1, 2, 6, 9, 7]
    )
    np.testing.assert_array_equal(faces.triangles, [WEDGE_FACES[0]])
