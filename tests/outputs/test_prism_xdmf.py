"""XDMF ``Wedge_18`` files of 18-node prism meshes (``outputs.prism_xdmf``, docs/method.md §43).

The node order is checked against basix's reference prism (all releases) and, on dolfinx 0.11,
from the file alone (``xml.etree``): the cells of a straight block have their midside and face
nodes at the midpoints of VTK's edges and quadrilaterals and positive volumes from VTK's outward
faces; the point data are the Functions' nodal values (an interpolated quadratic field, and a
C3D15 solution whose face centres keep their serendipity values); the file is the same on 1 and 2
processes.
"""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.quadratic_prisms import (
    END,
    build_prism_block,
    build_prism_sector,
    clamped_dofs,
    solve_wedge15,
)
from helpers.xdmf import read_xdmf

import basix
import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.serendipity_wedge import wedge15_space
from dolfinx_ntf.fem.wedge_faces import prism_face_forces
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh
from dolfinx_ntf.outputs.prism_xdmf import PRISM18_TO_VTK, PrismXdmfFile
from dolfinx_ntf.outputs.xdmf_cells import XDMF_WEDGE_18

COMM = MPI.COMM_WORLD
ON_011 = compat.DOLFINX_VERSION >= (0, 11)
needs_011 = pytest.mark.skipif(not ON_011, reason="degree-2 prisms need dolfinx 0.11 (§32.5)")

#: VTK_BIQUADRATIC_QUADRATIC_WEDGE (vtkBiQuadraticQuadraticWedge.h): edges of nodes 6..14 and
#: quadrilaterals of the centres 15..17.
VTK_EDGES = [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)]
VTK_QUADS = [(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)]
#: vtkWedge's faces, outward when 0-1-2's normal points away from 3-4-5 (as VTK documents).
VTK_FACES = [(0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)]


def _vtk_nodes(corners: np.ndarray) -> np.ndarray:
    """``(..., 18, 3)``: VTK's 18 nodes of straight wedges from their corners in VTK's order."""
    edges = [(corners[..., a, :] + corners[..., b, :]) / 2 for a, b in VTK_EDGES]
    quads = [corners[..., list(q), :].mean(axis=-2) for q in VTK_QUADS]
    return np.concatenate([corners, np.stack(edges + quads, axis=-2)], axis=-2)


def _corner_volumes(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Volumes of the corners' straight wedges from VTK's outward faces (divergence theorem)."""
    volume = np.zeros(cells.shape[0])
    for face in VTK_FACES:
        for k in range(1, len(face) - 1):
            a, b, c = (points[cells[:, face[j]]] for j in (0, k, k + 1))
            volume += np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    return volume


def test_order_is_vtks_biquadratic_wedge():
    """basix's degree-2 prism points in PRISM18_TO_VTK's order are VTK's wedge, turned as VTK's."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    points = element.points[PRISM18_TO_VTK]
    np.testing.assert_allclose(points, _vtk_nodes(points[:6]), atol=1e-15)
    assert _corner_volumes(points, np.arange(18)[None, :])[0] == pytest.approx(0.5)


def _field(x: np.ndarray) -> np.ndarray:
    """A quadratic vector field (exact in the P2 space)."""
    return np.vstack([x[0] ** 2 - x[1], x[0] * x[2] + 1.0, x[1] ** 2 + 2.0 * x[2]])


def _write(path: Path, comm: MPI.Comm, incomplete: bool) -> tuple[int, Path]:
    """The block with the quadratic field and its first component, two steps; the cell count."""
    mesh, _, _ = mesh_from_gmsh(build_prism_block, comm, incomplete=incomplete)
    V, _ = wedge15_space(mesh)
    u = dolfinx.fem.Function(V, name="u")
    u.interpolate(_field)
    Q = compat.scalar_space(mesh, "Lagrange", 2)
    s = dolfinx.fem.Function(Q, name="s")
    s.interpolate(lambda x: _field(x)[0])
    with PrismXdmfFile(path, mesh) as file:
        file.write(0.0, [u, s])
        u.x.array[:] *= 2.0
        file.write(1.0, [u])
    return comm.allreduce(mesh.topology.index_map(3).size_local, op=MPI.SUM), path


@pytest.mark.mpi
@needs_011
@pytest.mark.parametrize("incomplete", [True, False], ids=["15-node", "18-node"])
def test_prism_file_holds_mesh_and_values(tmp_path: Path, incomplete: bool):
    """Cells, VTK's order from the coordinates, point data = the Functions at the nodes."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    num_cells, path = _write(directory / "block.xdmf", COMM, incomplete)
    if COMM.rank != 0:
        return
    points, cells, steps = read_xdmf(path)
    assert len(cells) == num_cells > 0 and {k for k, _ in cells} == {XDMF_WEDGE_18}
    nodes = np.array([n for _, n in cells])
    assert np.unique(nodes).size == points.shape[0]  # every point in a cell
    np.testing.assert_allclose(points[nodes], _vtk_nodes(points[nodes[:, :6]]), atol=1e-13)
    volumes = _corner_volumes(points, nodes)
    assert (volumes > 0).all() and volumes.sum() == pytest.approx(2.0, rel=1e-13)
    assert [s["t"] for s in steps] == [0.0, 1.0]
    assert set(steps[0]) == {"t", "u", "s"} and set(steps[1]) == {"t", "u"}
    exact = _field(points.T).T
    np.testing.assert_allclose(steps[0]["u"], exact, atol=1e-13)
    np.testing.assert_allclose(steps[0]["s"][:, 0], exact[:, 0], atol=1e-13)
    np.testing.assert_allclose(steps[1]["u"], 2.0 * exact, atol=1e-13)


@pytest.mark.mpi
@needs_011
def test_prism_file_is_the_serial_file(tmp_path: Path):
    """The same file on 1 and 2 processes: the mesh text identical, the values to round-off."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    _, world = _write(directory / "world.xdmf", COMM, True)
    # every process writes its serial file (the gmsh reader waits on all processes)
    _, serial = _write(directory / f"serial{COMM.rank}.xdmf", MPI.COMM_SELF, True)
    if COMM.rank == 0:
        text, reference = world.read_text(), serial.read_text()
        mesh_end = reference.index('<Grid Name="TimeSeries"')
        assert text[:mesh_end] == reference[:mesh_end]
        for a, b in zip(read_xdmf(world)[2], read_xdmf(serial)[2], strict=True):
            assert a.keys() == b.keys()
            for name in set(a) - {"t"}:
                # interpolation pushes the nodes forward through another cell: round-off
                scale = np.abs(b[name]).max()
                np.testing.assert_allclose(a[name], b[name], rtol=0, atol=1e-14 * scale)
    COMM.barrier()


@pytest.mark.mpi
@needs_011
def test_c3d15_solution_keeps_its_face_centres(tmp_path: Path):
    """A C3D15 solution on the curved sector: each face centre in the file is its quad8 value."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    mesh, _, faces = mesh_from_gmsh(build_prism_sector, COMM, incomplete=True)
    V, constraints = wedge15_space(mesh)
    dofs = clamped_dofs(V, lambda x: np.isclose(x[0], 0.0), constraints)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), dofs, V)]
    u = solve_wedge15(V, constraints, bcs, prism_face_forces(V, faces, END, 10.0))
    u.name = "displacement"
    with PrismXdmfFile(directory / "sector.xdmf", mesh) as file:
        file.write(1.0, [u])
    if COMM.rank != 0:
        return
    points, cells, (step,) = read_xdmf(directory / "sector.xdmf")
    nodes = np.array([n for _, n in cells])
    assert (_corner_volumes(points, nodes) > 0).all()
    values = step["displacement"][nodes]  # (cells, 18, 3)
    largest = np.abs(values).max()
    assert largest > 0
    for k, quad in enumerate(VTK_QUADS):
        edges = [6 + e for e, (a, b) in enumerate(VTK_EDGES) if a in quad and b in quad]
        quad8 = -0.25 * values[:, list(quad)].sum(axis=1) + 0.5 * values[:, edges].sum(axis=1)
        assert np.abs(values[:, 15 + k] - quad8).max() <= 1e-12 * largest


@pytest.mark.mpi
@needs_011
def test_prism_file_refuses_other_meshes_and_spaces(tmp_path: Path):
    """A mesh of hexahedra, degree-1 and broken Functions on the prisms: refused with the reason."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    cube = dolfinx.mesh.create_unit_cube(COMM, 1, 1, 1, dolfinx.mesh.CellType.hexahedron)
    with pytest.raises(ValueError, match="a mesh of prisms is needed"):
        PrismXdmfFile(directory / "cube.xdmf", cube)
    mesh, _, _ = mesh_from_gmsh(build_prism_block, COMM, incomplete=True)
    linear = dolfinx.fem.Function(compat.vector_space(mesh, "Lagrange", 1), name="p1")
    broken = dolfinx.fem.Function(compat.discontinuous_space(mesh, 2), name="dg2")
    with PrismXdmfFile(directory / "p1.xdmf", mesh) as file:
        for f in (linear, broken):
            with pytest.raises(ValueError, match="degree-2 Lagrange spaces on the file's mesh"):
                file.write(0.0, [f])
