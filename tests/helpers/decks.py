"""Decks for the deck runner's tests, and the run of one deck serially and on all processes.

``deck_with_requests`` writes a stored or cross-validation deck with every output request;
``run_serial_and_parallel`` runs it on rank 0 alone and on ``COMM_WORLD``; ``run_summary`` and
``first_differing_file`` compare the two (docs/method.md §14.5).
"""

import re
import shutil
from pathlib import Path

from mpi4py import MPI

from dolfinx_ntf.calculix.job import run_job

COMM = MPI.COMM_WORLD
DATA = Path(__file__).parents[1] / "data" / "calculix"
#: ccx's test decks (Debian package calculix-ccx-test).
CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")

#: Output requests added to every step: all prints and all file outputs.
REQUESTS = (
    "*NODE PRINT, NSET=NALL, TOTALS=YES\nRF\n*EL PRINT, ELSET=EALL\nS\n"
    "*NODE FILE, CONTACT ELEMENTS\nU, RF\n*EL FILE\nS\n*CONTACT FILE\nCDIS, CSTR\n*END STEP"
)

#: Two C3D8 stacked along z (a unit cube), their shared layer warped (corners moved in z), with
#: symmetry planes x = 0, y = 0, the bottom held in z; material ``M`` with ``{E}, {NU}`` to fill.
WARPED_CUBES = """*NODE, NSET=NALL
1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
5, 0, 0, 0.45
6, 1, 0, 0.55
7, 1, 1, 0.5
8, 0, 1, 0.58
9, 0, 0, 1
10, 1, 0, 1
11, 1, 1, 1
12, 0, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 5, 6, 7, 8, 9, 10, 11, 12
*NSET, NSET=BOTTOM
1, 2, 3, 4
*NSET, NSET=XSYM
1, 4, 5, 8, 9, 12
*NSET, NSET=YSYM
1, 2, 5, 6, 9, 10
*BOUNDARY
BOTTOM, 3, 3
XSYM, 1, 1
YSYM, 2, 2
*MATERIAL, NAME=M
*ELASTIC
{E}, {NU}
*SOLID SECTION, ELSET=EALL, MATERIAL=M
"""

#: The corners of the unit cube in ccx's C3D8 order (bottom face, then top face).
UNIT_CUBE_CORNERS = ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
                     (0, 1, 1))  # fmt: skip
#: The unit cube's nodes 1-8 as ``*NODE`` data lines.
UNIT_CUBE_NODES = "".join(
    f"{k}, {x}, {y}, {z}\n" for k, (x, y, z) in enumerate(UNIT_CUBE_CORNERS, 1)
)
#: One C3D8 unit cube (nodes 1-8, element 1 in ELSET EALL) under ``*NODE, NSET=NALL``.
UNIT_C3D8 = (
    "*NODE, NSET=NALL\n"
    + UNIT_CUBE_NODES
    + "*ELEMENT, TYPE=C3D8, ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
)

#: Two unit C3D8 cubes side by side along x (nodes 1-12, elements 1, 2 in ELSET EALL), to follow
#: ``*NODE, NSET=NALL``.
TWO_C3D8 = (
    UNIT_CUBE_NODES
    + """9, 2, 0, 0
10, 2, 1, 0
11, 2, 0, 1
12, 2, 1, 1
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 2, 9, 10, 3, 6, 11, 12, 7
"""
)

#: metalforming's sheet: elastic, then isotropic hardening from yield at 1 % strain.
SHEET_ELASTIC = "*ELASTIC\n5000.0, 0.3\n"
SHEET_PLASTIC = "*PLASTIC\n50.0, 0.0\n100.0, 0.3\n"


def mixed_sections(plastic: bool = True) -> str:
    """Material cards of :func:`pulled_bar`: element 1 the sheet (``SHEET``), element 2 elastic."""
    return (
        "*ELSET, ELSET=E1\n1\n*ELSET, ELSET=E2\n2\n*MATERIAL, NAME=SHEET\n"
        + SHEET_ELASTIC
        + (SHEET_PLASTIC if plastic else "")
        + "*MATERIAL, NAME=ELASTIC\n"
        + SHEET_ELASTIC
        + "*SOLID SECTION, ELSET=E1, MATERIAL=SHEET\n*SOLID SECTION, ELSET=E2, MATERIAL=ELASTIC\n"
    )


def pulled_bar(
    sections: str,
    requests: str,
    nlgeom: str = "",
    heading: str = "",
    second_requests: str | None = None,
) -> str:
    """``TWO_C3D8`` on symmetry rollers, pulled to 5 % in ccx's automatic increments, then to 4 %.

    Args:
        sections: The ``*MATERIAL`` and ``*SOLID SECTION`` cards.
        requests: The output requests of both steps.
        nlgeom: ``", NLGEOM"`` or ``""``, after ``*STEP``.
        heading: A ``*HEADING`` line if not empty.
        second_requests: The second step's requests if not ``requests``.
    """
    steps = "".join(
        f"*STEP{nlgeom}\n*STATIC\n{start}, 1.0\n*CONTROLS, PARAMETERS=FIELD\n"
        "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12\n"
        f"*BOUNDARY\nEND, 1, 1, {end}\n{asked}*END STEP\n"
        for start, end, asked in (
            (0.125, 0.1, requests),
            (0.25, 0.08, requests if second_requests is None else second_requests),
        )
    )
    return (
        (f"*HEADING\n{heading}\n" if heading else "")
        + "*NODE, NSET=NALL\n"
        + TWO_C3D8
        + "*NSET, NSET=X0\n1, 4, 5, 8\n*NSET, NSET=Y0\n1, 2, 5, 6, 9, 11\n"
        "*NSET, NSET=Z0\n1, 2, 3, 4, 9, 10\n*NSET, NSET=END\n9, 10, 11, 12\n"
        + sections
        + "*BOUNDARY\nX0, 1, 1\nY0, 2, 2\nZ0, 3, 3\n"
        + steps
    )


_CLOCK = re.compile(r"^\s*1U(TIME|DATE)")  # .frd header lines with the wall-clock time


def _crossval(name: str, directory: Path) -> Path:
    """A cross-validation deck (tests/data/calculix/crossval) written on rank 0."""
    import cases
    import friction_cases

    (case,) = [c for c in cases.CASES + friction_cases.CASES if c.name == name]
    case.write(directory)
    return directory / f"{name}.inp"


def deck_with_requests(name: str, directory: Path) -> Path:
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


def run_serial_and_parallel(path: Path):
    """The deck on rank 0 alone (in ``serial/``) and on all processes; both results."""
    serial_dir = path.parent / "serial"
    serial, error = None, None
    if COMM.rank == 0:
        serial_dir.mkdir(exist_ok=True)
        shutil.copy(path, serial_dir / path.name)
        try:
            serial = run_job(path.stem, serial_dir, comm=MPI.COMM_SELF, progress=False)
        except Exception as exc:  # the other processes would wait in the parallel run
            error = f"the serial run failed: {exc!r}"
    error = COMM.bcast(error, root=0)
    assert error is None, error
    parallel = run_job(path.stem, path.parent, comm=COMM, progress=False)
    return serial, parallel, serial_dir


def first_differing_file(path: Path, serial_dir: Path) -> str | None:
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


def run_summary(result) -> dict:
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


def reference_node_deck(boundary: str) -> str:
    """contact1 whose upper cube's top is tied in z to node 99, in no element, by *EQUATION."""
    text = (CCX_TESTS / "contact1.inp").read_text()
    text = text.replace("*ELEMENT, TYPE=C3D8", "      99, 0.5, 0.5, 1.5\n*ELEMENT, TYPE=C3D8", 1)
    text = text.replace(
        "*NSET,NSET=Nfix \n1, \n2, \n5, \n6, \n11, \n12, \n15, \n16, \n",
        "*NSET,NSET=Nfix \n1, \n2, \n5, \n6, \n*NSET,NSET=Ntop\n11,12,15,16\n",
    )
    text = text.replace("Nfix,1,3\n", "Nfix,1,3\nNtop,1,2\n")
    ties = "".join(f"2\n{n},3,1.,99,3,-1.\n" for n in (11, 12, 15, 16))
    text = text.replace("*MATERIAL,NAME=EL", ties + "*MATERIAL,NAME=EL")
    text = text.replace("*CLOAD\n10,3,-1.\n", boundary)
    return text.replace("*STATIC\n", "*STATIC\n0.5,1.\n")
