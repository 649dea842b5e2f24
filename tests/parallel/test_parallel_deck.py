"""The deck runner on several processes writes the serial run's files (docs/method.md §14.5).

Each test runs a deck on ``COMM_SELF`` (rank 0, the reference) and on ``COMM_WORLD`` in the same
run, then compares the files, the Newton iteration counts and the contact elements. ``make
test-here`` runs this file on 2 processes and again on 3; in serial the comparisons are trivial.

The ``.dat``, ``.cel``, ``.sta``, ``.cvg`` and ``.frd`` files must be byte-identical (the
``.frd`` header's two clock lines aside): the ``.cel`` and ``.cvg`` files hold every Newton
iteration's contact elements and residual. Values below their accuracy (round-off, forces within
the Newton residual) are written as 0 in serial and in parallel alike
(``dolfinx_ntf/calculix/roundoff.py``). Partitions: dolfinx's graph partitioner, and ``empty``
(slices along x on all processes but the last, which holds no cell).
"""

import shutil
import tempfile
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.decks import (
    REQUESTS,
    deck_with_requests,
    first_differing_file,
    reference_node_deck,
    run_serial_and_parallel,
    run_summary,
)

from dolfinx_ntf import compat
from dolfinx_ntf.__main__ import EXIT_INPUT, main
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.model import build_model
from dolfinx_ntf.calculix.model import calculix_model as model_module

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
DATA = Path(__file__).parents[1] / "data" / "calculix"


@pytest.fixture(scope="module")
def shared():
    """A directory all processes see (created by rank 0)."""
    path = Path(tempfile.mkdtemp(prefix="ntf-deck-")) if COMM.rank == 0 else None
    path = COMM.bcast(path, root=0)
    yield path
    COMM.barrier()
    if COMM.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


def _assert_serial_files(path: Path, *, in_contact: bool = True):
    """Run the deck serially and on all processes: same iterations, contact elements, nodes and
    displacements (1e-10), and the same files (:func:`first_differing_file`). Returns the parallel
    result.

    ``in_contact``: the serial run must have contact elements.
    """
    serial, parallel, serial_dir = run_serial_and_parallel(path)
    serial = COMM.bcast(serial and run_summary(serial), root=0)
    assert run_summary(parallel)["iterations"] == serial["iterations"]
    assert run_summary(parallel)["contact"] == serial["contact"]
    u, u_ref = parallel.last.displacement, serial["displacement"]
    assert np.array_equal(parallel.last.node_ids, serial["node_ids"])
    assert np.max(np.abs(u - u_ref)) <= 1e-10 * np.max(np.abs(u_ref))
    if in_contact:
        assert any(nodes for increment in serial["contact"] for _, nodes, _ in increment)
    files = first_differing_file(path, serial_dir) if COMM.rank == 0 else None
    files = COMM.bcast(files, root=0)
    assert files is None, files
    return parallel


DECKS = [
    "two_cubes",  # C3D8, two elements (on 3 processes one holds none), *CONTACT PRINT, TOTALS
    "hex_linear_pressure",  # C3D8 punch, *DLOAD, 3 increments
    "tet_linear_two_steps",  # C3D4, two steps
    "tet10_exponential",  # C3D10, 6-node faces
    "hex_two_pairs",  # C3D8, two pairs, *CLOAD
    "hex_tabular_nodal",  # C3D8, node-based slave starting on the master, TABULAR law
]


@pytest.mark.parametrize("name", DECKS)
def test_deck_gives_the_serial_files(name, shared):
    path = deck_with_requests(name, shared)
    _assert_serial_files(path)


def test_wedge_deck_gives_the_serial_files(shared):
    """C3D6 wedges (collapsed C3D8, docs/method.md §30), their triangles the master faces."""
    path = shared / "wedge_punch" / "wedge_punch.inp"
    if COMM.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text((DATA / "wedge_punch.inp").read_text())
    COMM.barrier()
    _assert_serial_files(path)


def _interior_face(path: Path) -> tuple[int, int]:
    """An element face between two elements of the deck: (element, face number)."""
    deck = read_deck(path)
    block = next(b for b in deck.elements.values() if b.ids.size)
    faces = block.connectivity[:, block.type.faces[:, : block.type.face_corners]]
    keys = np.sort(faces.reshape(-1, block.type.face_corners), axis=1)
    _, first, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    k = int(first[np.argmax(counts > 1)])
    return int(block.ids[k // faces.shape[1]]), k % faces.shape[1] + 1


def test_bad_face_found_by_one_process_fails_on_all(shared):
    path = deck_with_requests("hex_linear_pressure", shared / "bad")
    if COMM.rank == 0:
        element, face = _interior_face(path)
        text = path.read_text().replace(
            "*STEP", f"*SURFACE, NAME=INSIDE\n{element}, S{face}\n*STEP", 1
        )
        path.write_text(text)
    COMM.barrier()
    with pytest.raises(ValueError, match="lies between two elements, not on the boundary"):
        run_job(path.stem, path.parent, comm=COMM, progress=False)


def test_bad_deck_fails_on_every_process(shared):
    path = shared / "broken" / "broken.inp"
    if COMM.rank == 0:
        path.parent.mkdir(exist_ok=True)
        text = (DATA / "two_cubes.inp").read_text()
        path.write_text(text.replace("*SOLID SECTION, ELSET=EALL", "*SOLID SECTION, ELSET=NONE"))
    COMM.barrier()
    with pytest.raises(ValueError, match="NONE"):
        run_job("broken", path.parent, comm=COMM, progress=False)
    assert main(["run", str(path)]) == EXIT_INPUT  # the command line: same status everywhere
    assert main(["run", str(path.parent / "missing")]) == EXIT_INPUT


FRICTION_DECKS = [
    "hex_stick_punch",  # friction: press, then drag (stick)
    "hex_sliding_block",  # slip, *CHANGE FRICTION, *MODEL CHANGE REMOVE/ADD, five steps
    "hex_adjust_gap",  # ADJUST by distance, friction
    "tet_adjust_set",  # ADJUST by node set
]


@pytest.mark.parametrize("name", FRICTION_DECKS)
def test_friction_and_adjust_decks_give_the_serial_files(name, shared):
    """Friction state on the slave node's owner, ADJUST moves on every process (§14.6)."""
    path = deck_with_requests(name, shared / "friction")
    _assert_serial_files(path, in_contact=False)


def _hex20(name: str, directory: Path) -> Path:
    """``two_cubes`` as a C3D20 deck (2 elements: on 3 processes one holds none), on rank 0."""
    path = directory / name / f"{name}.inp"
    if COMM.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        lines = (DATA / "two_cubes.inp").read_text().replace("*END STEP", REQUESTS).splitlines()
        path.write_text("\n".join(x for x in lines if not x.startswith("**")) + "\n")
        from hex20 import to_hex20

        to_hex20(path)
    COMM.barrier()
    return path


HEX20_DECKS = [
    "two_cubes_hex20",  # C3D20, 2 elements (on 3 processes one holds none)
    "hex20_linear_pressure",  # C3D20 punch, quad8 faces, *DLOAD, 2 increments
    "hex20r_exponential",  # C3D20R, initial gap, prescribed displacement, 3 increments
    "hex20_nodal",  # C3D20, node-based slave surface with midside nodes, TABULAR
]


@pytest.mark.parametrize("name", HEX20_DECKS)
def test_c3d20_deck_gives_the_serial_files(name, shared):
    """Serendipity rows of all processes, a shared face's row once; RF on the 20 nodes (§14.10)."""
    directory = shared / "c3d20"
    path = (
        _hex20(name, directory)
        if name == "two_cubes_hex20"
        else deck_with_requests(name, directory)
    )
    parallel = _assert_serial_files(path)
    assert parallel.model.element_type.name in ("C3D20", "C3D20R")


def _dynamic(name: str, directory: Path) -> Path:
    """A ``*DYNAMIC`` deck with every output request, on rank 0; its path on every process.

    ``impact``: a block moving onto a base (tests/data/calculix/dynamic), DIRECT increments;
    ``impact_auto``: the same with automatic increments; ``two_cubes_dynamic``: two_cubes (2
    elements: on 3 processes one holds none) pressed in a dynamic step.
    """
    path = directory / name / f"{name}.inp"
    if COMM.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        if name == "two_cubes_dynamic":
            text = (DATA / "two_cubes.inp").read_text()
            text = text.replace("210000., 0.3\n", "210000., 0.3\n*DENSITY\n7.8e-9\n")
            text = text.replace("*STATIC\n0.5, 1.0", "*DYNAMIC, DIRECT\n2e-6, 1e-5")
        else:
            from impact_deck import write_impact_deck

            direct = name == "impact"
            text = write_impact_deck(
                path.parent, name, period=0.02, increment=1e-3, direct=direct
            ).read_text()
        path.write_text(text.replace("*END STEP", REQUESTS))
    COMM.barrier()
    return path


DYNAMIC_DECKS = ["impact", "impact_auto", "two_cubes_dynamic"]


@pytest.mark.parametrize("name", DYNAMIC_DECKS)
def test_dynamic_deck_gives_the_serial_files(name, shared):
    """Mass, velocity and acceleration distributed like the displacement (§14.10).

    Byte-identical files: the stresses of the block in free flight and its contact values at the
    touching time are round-off only, within the accuracy of the displacement (§14.5).
    """
    path = _dynamic(name, shared / "dynamic")
    _assert_serial_files(path)


# ----------------------------------------------------------------------------- *EQUATION

CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")


def _equation_deck(name: str) -> str:
    """ccx's *EQUATION decks (§13.1) and variants: a tie across the two cubes, reference nodes."""

    if name in ("contact1", "contact3", "contact6"):
        return (CCX_TESTS / f"{name}.inp").read_text()
    if name == "contact1_across":  # node 14 (upper cube) on nodes 10 (upper) and 3 (lower)
        text = (CCX_TESTS / "contact1.inp").read_text()
        return text.replace("2\n14,3,1.,10,3,-1.\n", "3\n14,3,1.,10,3,-1.,3,3,0.001\n")
    if name == "reference_prescribed":  # the upper top tied to node 99 (no element), prescribed
        return reference_node_deck("*BOUNDARY\n99,3,3,-1.E-6\n")
    return reference_node_deck("*CLOAD\n99,3,-1.\n")  # ... free and loaded


EQUATION_DECKS = [
    "contact1",
    "contact3",
    "contact6",
    "contact1_across",
    "reference_prescribed",
    "reference_free",
]


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
@pytest.mark.parametrize("name", EQUATION_DECKS)
def test_equation_decks_give_the_serial_files(name, shared):
    """*EQUATION terms on nodes of any process, numbered globally (docs/method.md §14.9)."""
    path = shared / "equation" / name / f"{name}.inp"
    if COMM.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(_equation_deck(name).replace("*END STEP", REQUESTS))
    COMM.barrier()
    if name == "contact1_across" and COMM.size == 2:  # the cubes on different processes (on 3,
        # dolfinx's partitioner puts both on one and leaves two processes without a cell)
        model = build_model(read_deck(path), COMM)
        held = COMM.allgather(set(model.dof_node[model.dof_node > 0].tolist()))
        assert not any({3, 10, 14} <= nodes for nodes in held)
    _assert_serial_files(path)


def _sliced_mesh(deck, block, comm, carried=None):
    """``create_mesh`` with the ``empty`` partition: slices along x on all processes but
    the last, which holds no cell (on one process, everything on it). Decks with nodes in no
    element (``carried``) are not among its decks."""
    assert carried is None or len(carried) == 0
    domain = compat.coordinate_element(block.type.cell, block.type.degree)
    cells = np.zeros((0, block.type.num_nodes), dtype=np.int64)
    x, owners = np.zeros((0, 3)), np.zeros(0, dtype=np.int32)
    if comm.rank == 0:
        cells = deck.node_index(block.connectivity)[:, block.type.to_dolfinx]
        x = np.asarray(deck.node_coords, dtype=np.float64)
        middle = x[cells, 0].mean(axis=1)
        lo, hi = x[:, 0].min(), x[:, 0].max()
        others = max(comm.size - 1, 1)
        owners = np.minimum(((middle - lo) / (hi - lo) * others).astype(np.int32), others - 1)
    return compat.create_mesh(comm, cells, x, domain, owners)


@pytest.mark.parametrize("name", ["hex_linear_pressure", "hex_stick_punch"])
def test_process_without_cells_gives_the_serial_files(name, shared, monkeypatch):
    """The last process holds no cell (a *DLOAD deck and a friction deck)."""
    monkeypatch.setattr(model_module, "create_mesh", _sliced_mesh)
    path = deck_with_requests(name, shared / "empty")
    _assert_serial_files(path, in_contact=False)
