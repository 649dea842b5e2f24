"""``JOB.xdmf`` of C3D15 decks (docs/method.md §43): XDMF ``Wedge_15`` cells at the deck's nodes.

dolfinx 0.11 writes no 18-node prisms, so the deck runner writes the deck's own mesh: every C3D15
as a ``Wedge_15`` (``VTK_QUADRATIC_WEDGE``) cell of its 15 deck nodes, the fields gathered in ccx
order on rank 0. Checked here from the file alone (``xml.etree``): the points are the deck's
nodes; each cell's corners are its element's, turned as VTK documents (the first triangle's
normal away from the second) so that the cells' volumes from VTK's outward faces are positive and
sum to the block's; each midside slot holds the element's node of that edge (ccx's edge table,
not the writer's permutation); the displacement is the ``.dat`` file's U of every increment; the
file is the same on 1 and 2 processes. On dolfinx 0.5.2 and 0.9 C3D15 decks stay refused
(``test_calculix_c3d15.py``).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.xdmf import read_xdmf

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.outputs.xdmf_cells import XDMF_WEDGE_15

COMM = MPI.COMM_WORLD
DATA = Path(__file__).parent.parent / "data" / "calculix" / "c3d15"
ON_011 = compat.DOLFINX_VERSION >= (0, 11)

#: ccx's C3D15 (manual): nodes 7..15 on the edges 1-2, 2-3, 3-1, 4-5, 5-6, 6-4, 1-4, 2-5, 3-6.
CCX_EDGES = [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)]
#: VTK_QUADRATIC_WEDGE (vtkQuadraticWedge.h): midside nodes 6..14 on these edges.
VTK_EDGES = [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)]
#: vtkWedge's faces, outward when 0-1-2's normal points away from 3-4-5 (as VTK documents).
VTK_FACES = [(0, 1, 2), (3, 5, 4), (0, 3, 4, 1), (1, 4, 5, 2), (2, 5, 3, 0)]

pytestmark = pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (method §32.5)")


def _run(directory: Path, job: str, comm: MPI.Comm) -> Path:
    if comm.rank == 0:
        directory.mkdir(parents=True, exist_ok=True)
        shutil.copy(DATA / f"{job}.inp", directory / f"{job}.inp")
    comm.barrier()
    result = run_job(job, directory, comm=comm, progress=False)
    assert result.completed and result.xdmf == directory / f"{job}.xdmf"
    return result.xdmf


def _corner_volumes(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Volumes of the corners' straight wedges from VTK's outward faces (divergence theorem)."""
    volume = np.zeros(cells.shape[0])
    for face in VTK_FACES:
        for k in range(1, len(face) - 1):  # a fan of triangles
            a, b, c = (points[cells[:, face[j]]] for j in (0, k, k + 1))
            volume += np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0
    return volume


@pytest.mark.mpi
@pytest.mark.parametrize("job, volume", [("wedge_block_nlgeom", 2.0), ("c3d15_dload", None)])
def test_c3d15_deck_writes_wedge15_xdmf(tmp_path: Path, job: str, volume: float | None) -> None:
    """The mesh, VTK's node order and orientation, and U of every increment (1 and 2 processes)."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    path = _run(directory / "world", job, COMM)
    if COMM.rank != 0:
        return
    deck = read_deck(directory / "world" / f"{job}.inp")
    points, cells, steps = read_xdmf(path)
    np.testing.assert_array_equal(points, deck.node_coords)
    block = deck.elements["C3D15"]
    assert len(cells) == block.ids.size and {k for k, _ in cells} == {XDMF_WEDGE_15}
    nodes = np.array([n for _, n in cells])
    elements = deck.node_index(block.connectivity)  # ccx order
    np.testing.assert_array_equal(np.sort(nodes, axis=1), np.sort(elements, axis=1))
    corners = nodes[:, :6]
    np.testing.assert_array_equal(np.sort(corners, axis=1), np.sort(elements[:, :6], axis=1))
    ccx_edge = [
        {frozenset(e[list(pair)].tolist()): e[6 + k] for k, pair in enumerate(CCX_EDGES)}
        for e in elements
    ]
    for cell, edges in zip(nodes, ccx_edge):
        for k, (a, b) in enumerate(VTK_EDGES):
            assert cell[6 + k] == edges[frozenset((cell[a], cell[b]))]
    p = points[corners]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert (np.einsum("ij,ij->i", normal, p[:, 3:].mean(1) - p[:, :3].mean(1)) < 0).all()
    volumes = _corner_volumes(points, nodes)
    assert (volumes > 0).all()
    if volume is not None:  # the block's corners lie on its straight grid
        assert volumes.sum() == pytest.approx(volume, rel=1e-13)
    blocks = [b for b in read_dat(directory / "world" / f"{job}.dat") if b.name == "U"]
    assert [s["t"] for s in steps] == [b.time for b in blocks]
    names = {
        "displacement",
        "contact_pressure",
        "contact_clearance",
        "contact_status",
        "contact_shear",
        "contact_slip",
        "contact_pressure_recovered",
    }
    for step, u in zip(steps, blocks):
        assert set(step) - {"t"} == names
        assert step["contact_pressure"].shape == (points.shape[0], 1)
        assert not step["contact_status"].any()  # these decks have no contact pairs
        largest = np.abs(u.values).max()
        rows = deck.node_index(u.labels)
        error = np.abs(step["displacement"][rows] - u.values).max()
        assert error <= 1e-6 * largest  # ccx's printed digits


@pytest.mark.mpi
def test_c3d15_xdmf_is_the_serial_file(tmp_path: Path) -> None:
    """On 2 processes the file is the serial run's: the same mesh text, U to round-off."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    world = _run(directory / "world", "wedge_block", COMM)
    if COMM.rank == 0:
        serial = _run(directory / "serial", "wedge_block", MPI.COMM_SELF)
        text, reference = world.read_text(), serial.read_text()
        mesh_end = reference.index('<Grid Name="TimeSeries"')
        assert text[:mesh_end] == reference[:mesh_end]
        _, _, steps = read_xdmf(world)
        _, _, expected = read_xdmf(serial)
        assert len(steps) == len(expected) == 1
        for name, values in expected[0].items():
            scale = max(np.abs(values).max(), 1e-300)
            assert np.abs(steps[0][name] - values).max() <= 1e-12 * scale, name
    COMM.barrier()


@pytest.mark.mpi
@pytest.mark.parametrize("job", ["wedge_punch_quad", "wedge_punch_mixed"])
def test_c3d15_contact_deck_writes_its_contact_fields(tmp_path: Path, job: str) -> None:
    """A C3D15 contact deck's file holds the springs' pressures: the ``.dat``'s CSTR, each step."""
    directory = Path(COMM.bcast(str(tmp_path), root=0))
    path = _run(directory / "world", job, COMM)
    if COMM.rank != 0:
        return
    deck = read_deck(directory / "world" / f"{job}.inp")
    _, _, steps = read_xdmf(path)
    blocks = [b for b in read_dat(directory / "world" / f"{job}.dat") if b.name == "CSTR"]
    assert len(blocks) == len(steps) > 0
    for step, cstr in zip(steps, blocks):
        assert step["t"] == pytest.approx(cstr.time, abs=1e-12)
        rows = deck.node_index(cstr.labels)
        pressure = cstr.values[:, 0]
        largest = np.abs(pressure).max()
        assert largest > 0
        np.testing.assert_allclose(step["contact_pressure"][rows, 0], pressure, atol=1e-6 * largest)
        np.testing.assert_array_equal(step["contact_status"][rows, 0] > 0, pressure > 0)
        others = np.setdiff1d(np.arange(deck.node_coords.shape[0]), rows)
        assert not step["contact_pressure"][others].any()
