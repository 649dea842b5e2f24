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

import re
import shutil
import sys
import tempfile
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf import compat
from dolfinx_ntf.__main__ import EXIT_INPUT, main
from dolfinx_ntf.calculix import model as model_module
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.model import build_model

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
DATA = Path(__file__).parent / "data" / "calculix"

#: Output requests added to every step: all prints and all file outputs.
REQUESTS = (
    "*NODE PRINT, NSET=NALL, TOTALS=YES\nRF\n*EL PRINT, ELSET=EALL\nS\n"
    "*NODE FILE, CONTACT ELEMENTS\nU, RF\n*EL FILE\nS\n*CONTACT FILE\nCDIS, CSTR\n*END STEP"
)

_CLOCK = re.compile(r"^\s*1U(TIME|DATE)")  # .frd header lines with the wall-clock time


@pytest.fixture(scope="module")
def shared():
    """A directory all processes see (created by rank 0)."""
    path = Path(tempfile.mkdtemp(prefix="ntf-deck-")) if COMM.rank == 0 else None
    path = COMM.bcast(path, root=0)
    yield path
    COMM.barrier()
    if COMM.rank == 0:
        shutil.rmtree(path, ignore_errors=True)


def _crossval(name: str, directory: Path) -> Path:
    """A cross-validation deck (tests/data/calculix/crossval) written on rank 0."""
    sys.path.insert(0, str(DATA / "crossval"))
    try:
        import cases
        import friction_cases
    finally:
        sys.path.pop(0)
    (case,) = [c for c in cases.CASES + friction_cases.CASES if c.name == name]
    case.write(directory)
    return directory / f"{name}.inp"


def _deck(name: str, directory: Path) -> Path:
    """Deck ``name`` with every output request, on rank 0; its path on every process."""
    path = directory / name / f"{name}.inp"
    if COMM.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
        source = DATA / f"{name}.inp"
        if not source.exists():
            source = _crossval(name, path.parent)
        path.write_text(source.read_text().replace("*END STEP", REQUESTS))
    COMM.barrier()
    return path


def _first_difference(serial: str, parallel: str) -> str:
    """The first line that differs (the .frd clock lines skipped), for the failure message."""
    a = [x for x in serial.splitlines() if not _CLOCK.match(x)]
    b = [x for x in parallel.splitlines() if not _CLOCK.match(x)]
    for k, (x, y) in enumerate(zip(a, b)):
        if x != y:
            return f"line {k + 1}: {x!r} != {y!r}"
    return f"{len(a)} lines in serial, {len(b)} in parallel"


def _run_both(path: Path):
    """The deck on rank 0 alone (in ``serial/``) and on all processes; both results."""
    serial_dir = path.parent / "serial"
    serial = None
    if COMM.rank == 0:
        serial_dir.mkdir(exist_ok=True)
        shutil.copy(path, serial_dir / path.name)
        serial = run_job(path.stem, serial_dir, comm=MPI.COMM_SELF, progress=False)
    COMM.barrier()
    parallel = run_job(path.stem, path.parent, comm=COMM, progress=False)
    return serial, parallel, serial_dir


def _check_files(path: Path, serial_dir: Path) -> str | None:
    """Rank 0: the first file that differs from the serial one (None when all are identical)."""
    for suffix in (".sta", ".cel", ".dat", ".cvg", ".frd"):
        a, b = serial_dir / (path.stem + suffix), path.with_suffix(suffix)
        if not (a.exists() or b.exists()):
            continue
        if not (a.exists() and b.exists()):
            return f"{b.name}: written in one run only"
        serial, parallel = a.read_text(), b.read_text()
        if suffix == ".frd":  # the header's wall-clock date and time
            serial = "\n".join(x for x in serial.splitlines() if not _CLOCK.match(x))
            parallel = "\n".join(x for x in parallel.splitlines() if not _CLOCK.match(x))
        if serial != parallel:
            return f"{b.name} differs from the serial file: {_first_difference(serial, parallel)}"
    return None


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
    path = _deck(name, shared)
    serial, parallel, serial_dir = _run_both(path)
    serial = COMM.bcast(serial and _summary(serial), root=0)
    assert _summary(parallel)["iterations"] == serial["iterations"]
    assert _summary(parallel)["contact"] == serial["contact"]
    u, u_ref = parallel.last.displacement, serial["displacement"]
    assert np.array_equal(parallel.last.node_ids, serial["node_ids"])
    assert np.max(np.abs(u - u_ref)) <= 1e-10 * np.max(np.abs(u_ref))
    assert any(nodes for increment in serial["contact"] for _, nodes, _ in increment)
    error = _check_files(path, serial_dir) if COMM.rank == 0 else None
    error = COMM.bcast(error, root=0)
    assert error is None, error


def _summary(result) -> dict:
    """Iterations, contact elements (slave node, master face) per increment, last displacement."""
    return {
        "iterations": [(i.step, i.increment, i.attempt, i.iterations) for i in result.increments],
        "contact": [
            [(r.pair, r.nodes.tolist(), r.master_faces.tolist()) for r in i.contact]
            for i in result.increments
        ],
        "node_ids": result.last.node_ids,
        "displacement": result.last.displacement,
    }


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
    path = _deck("hex_linear_pressure", shared / "bad")
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
    path = _deck(name, shared / "friction")
    serial, parallel, serial_dir = _run_both(path)
    serial = COMM.bcast(serial and _summary(serial), root=0)
    assert _summary(parallel)["iterations"] == serial["iterations"]
    assert _summary(parallel)["contact"] == serial["contact"]
    u, u_ref = parallel.last.displacement, serial["displacement"]
    assert np.max(np.abs(u - u_ref)) <= 1e-10 * np.max(np.abs(u_ref))
    error = _check_files(path, serial_dir) if COMM.rank == 0 else None
    error = COMM.bcast(error, root=0)
    assert error is None, error


def test_c3d20_deck_refused_on_every_process(shared):
    """C3D20's added face and cell centres are not gathered in ccx numbering: one process only."""
    path = _deck("hex20_linear_pressure", shared / "c3d20")
    if COMM.size == 1:  # serial: the same deck is accepted
        model = build_model(read_deck(path), COMM)
        assert model.element_type.name == "C3D20"
        return
    with pytest.raises(NotImplementedError, match=rf"C3D20 elements on {COMM.size} MPI processes"):
        run_job(path.stem, path.parent, comm=COMM, progress=False)


def _sliced_mesh(deck, block, comm):
    """``model._create_mesh`` with the ``empty`` partition: slices along x on all processes but
    the last, which holds no cell (on one process, everything on it)."""
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
    monkeypatch.setattr(model_module, "_create_mesh", _sliced_mesh)
    path = _deck(name, shared / "empty")
    serial, parallel, serial_dir = _run_both(path)
    serial = COMM.bcast(serial and _summary(serial), root=0)
    assert _summary(parallel)["iterations"] == serial["iterations"]
    assert _summary(parallel)["contact"] == serial["contact"]
    u, u_ref = parallel.last.displacement, serial["displacement"]
    assert np.max(np.abs(u - u_ref)) <= 1e-10 * np.max(np.abs(u_ref))
    error = _check_files(path, serial_dir) if COMM.rank == 0 else None
    error = COMM.bcast(error, root=0)
    assert error is None, error
