"""C3D15 wedges (docs/method.md §34): run on dolfinx 0.11, refused naming the line before it.

The decks are ``tests/data/calculix/c3d15/make_block.py``'s C3D15 block (curved edges, uneven
load; small strain, NLGEOM, pressures on curved faces) and ccx's own ``c3d15.inp``
(``make_variants.py``: as given but for what the reader refuses, and with its pressures as
nodal forces); the ``.dat.ref`` files are ccx 2.20's output.
"""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.elements import ELEMENT_TYPES
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job

DATA = Path(__file__).parent.parent / "data" / "calculix" / "c3d15"
ON_011 = compat.DOLFINX_VERSION >= (0, 11)


def _run(tmp_path: Path, job: str, comm: MPI.Comm = MPI.COMM_SELF) -> tuple[list, list]:
    """ccx's stored blocks and ours (rank 0's directory for all processes; both on every one)."""
    root = Path(comm.bcast(str(tmp_path), root=0))
    if comm.rank == 0:
        shutil.copy(DATA / f"{job}.inp", root / f"{job}.inp")
    comm.barrier()
    run_job(job, root, comm=comm, progress=False)
    comm.barrier()
    return read_dat(DATA / f"{job}.dat.ref"), read_dat(root / f"{job}.dat")


def _check(ccx: list, ours: list, free_rf: float) -> dict[str, float]:
    """Largest differences per block kind relative to ccx's largest value of that block.

    ccx's RF at free nodes is its last residual (ours prints 0 there): below ``free_rf`` of the
    block's largest value.
    """
    assert [(b.name, b.time) for b in ccx] == pytest.approx([(b.name, b.time) for b in ours])
    worst: dict[str, float] = {}
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(a.labels, b.labels)
        diff = np.abs(a.values - b.values)
        if a.name == "RF":  # ccx prints its last residual at free nodes; ours 0 there
            diff = diff[np.abs(b.values).max(axis=1) > 0]
            free = a.values[np.abs(b.values).max(axis=1) == 0]
            assert free.size == 0 or np.abs(free).max() < free_rf * np.abs(a.values).max()
        scale = np.abs(a.values).max()
        worst[a.name] = max(worst.get(a.name, 0.0), float(diff.max() / scale))
    return worst


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
@pytest.mark.parametrize(
    "job",
    [
        "wedge_block",
        "wedge_block_pressure",
        "wedge_block_dynamic",
        "wedge_block_modal",
        "c3d15",
        "c3d15_dload",
        "c3d15_cload",
    ],
)
def test_c3d15_small_strain_matches_ccx(tmp_path, job):
    """U, RF and S at ccx's 9 points equal ccx 2.20's printed digits (serial, 2 processes).

    ``wedge_block_pressure``: pressures on curved 6-node triangles (ccx's 3 points) and curved
    8-node quadrilaterals (ccx's 2 x 2 points; 3 x 3 differ by 3.9e-5). ``wedge_block_dynamic``
    (*DYNAMIC) and ``wedge_block_modal`` (*MODAL DYNAMIC: U only, as ccx prints it).
    ``c3d15``: ccx's own deck as Debian ships it (its identity ``*ORIENTATION``, ``*ELASTIC,
    TYPE=ISOTROPIC`` with a temperature column; method §41).
    """
    ccx, ours = _run(tmp_path, job, MPI.COMM_WORLD)
    worst = _check(ccx, ours, free_rf=1e-12)
    for name, value in worst.items():  # U, RF, S to ccx's printed digits
        assert value < 1e-6, (name, value)


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
@pytest.mark.parametrize(
    "job, free_rf, bound",
    [
        ("wedge_block_nlgeom", 1e-4, 1e-6),  # ccx stops at 0.5 % of its mean force
        ("wedge_block_pressure_nlgeom", 1e-10, 1e-6),  # tight controls; follower pressures
    ],
)
def test_c3d15_nlgeom_matches_ccx(tmp_path, job, free_rf, bound):
    """NLGEOM: ccx's 4 increments, U, RF, S and E to its printed digits (serial, 2 processes).

    With pressures on the current faces (``FollowerPressure``, tight controls in both codes):
    within a few units of the last printed digit (5.6e-7 of the largest U, 7.7e-8 of S).
    """
    ccx, ours = _run(tmp_path, job, MPI.COMM_WORLD)
    assert {b.time for b in ours} == {0.25, 0.5, 0.875, 1.0}  # ccx's increments
    worst = _check(ccx, ours, free_rf=free_rf)
    assert set(worst) == {"U", "RF", "S", "E"}
    assert all(value < bound for value in worst.values()), worst


@pytest.mark.skipif(ON_011, reason="dolfinx 0.11 runs C3D15")
def test_c3d15_refused_before_dolfinx_011(tmp_path):
    shutil.copy(DATA / "wedge_block.inp", tmp_path / "wedge_block.inp")
    with pytest.raises(NotImplementedError) as info:
        run_job("wedge_block", tmp_path, progress=False)
    message = str(info.value)
    assert "wedge_block.inp:" in message and "C3D15 (element 1)" in message
    assert "dolfinx 0.11" in message
    why = "refuses forms on prisms" if compat.DOLFINX_VERSION < (0, 7) else "abort the process"
    assert why in message


@pytest.mark.skipif(not ON_011, reason="the refusals of a C3D15 deck on dolfinx 0.11")
def test_c3d15_refuses_mixed_pressure_steps_and_mixed_meshes(tmp_path):
    deck = (DATA / "wedge_block_pressure.inp").read_text()
    (tmp_path / "p.inp").write_text(deck + "*STEP, NLGEOM\n*STATIC\n*END STEP\n")
    match = r"p\.inp:\d+: \*DLOAD pressures on C3D15 faces in a deck that mixes NLGEOM"
    with pytest.raises(NotImplementedError, match=match):
        run_job("p", tmp_path, progress=False)
    deck = (DATA / "wedge_block.inp").read_text()
    extra = "*ELEMENT, TYPE=C3D8, ELSET=EALL\n99, 1, 2, 3, 4, 5, 6, 7, 8\n*MATERIAL"
    (tmp_path / "m.inp").write_text(deck.replace("*MATERIAL", extra, 1))
    with pytest.raises(ValueError, match="C3D15 wedges run in meshes of C3D15 only"):
        run_job("m", tmp_path, progress=False)


def test_ccx_deck_variant_is_ccx_c3d15(tmp_path):
    """``c3d15_dload.inp`` is ccx's c3d15.inp with TYPE=ISO, no identity *ORIENTATION and no
    temperature column, ``c3d15_cload.inp`` also with its pressures as nodal forces: their ccx
    output (the stored references) equals ccx's own reference, and so does ccx's output of the
    unedited deck (``c3d15.dat.ref``, every byte)."""
    ref = Path("/usr/share/doc/calculix-ccx-test/examples/test/c3d15.dat.ref.gz")
    if not ref.exists():
        pytest.skip("calculix-ccx-test is not installed")
    with gzip.open(ref, "rt") as f:
        text = f.read()
    path = tmp_path / "c3d15.dat"
    path.write_text(text)
    theirs = read_dat(path)
    assert (DATA / "c3d15.dat.ref").read_text() == text
    for variant in ("c3d15_dload", "c3d15_cload"):
        ours = read_dat(DATA / f"{variant}.dat.ref")
        for a, b in zip(theirs, ours, strict=True):
            scale = np.abs(a.values).max()
            np.testing.assert_allclose(b.values, a.values, atol=1e-11 * scale + 1e-18)


@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_frd_elements_in_ccx_order(tmp_path):
    """``.frd`` element records: type 5 with ccx 2.20's node order 1..9, 13..15, 10..12 (as
    ccx's .frd of ``wedge_block.inp``, whose element 1 is nodes 1..15)."""
    _run(tmp_path, "wedge_block")
    lines = (tmp_path / "wedge_block.frd").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.split()[:3] == ["-1", "1", "5"])
    nodes = [int(t) for line in lines[start + 1 : start + 3] for t in line.split()[1:]]
    assert nodes == [*range(1, 10), 13, 14, 15, 10, 11, 12]


@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_mirrored_element_is_refused(tmp_path):
    """An element numbered against ccx's order (top and bottom triangles swapped) is refused
    naming it and its line, instead of a wrong answer."""
    lines = (DATA / "wedge_block.inp").read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if line.startswith("*ELEMENT")) + 3  # element 2
    first = [t.strip() for t in lines[k].split(",") if t.strip()]
    second = [t.strip() for t in lines[k + 1].split(",") if t.strip()]
    nodes = first[1:] + second
    swapped = nodes[3:6] + nodes[0:3] + nodes[9:12] + nodes[6:9] + nodes[12:15]
    lines[k] = ", ".join([first[0], *swapped[:9]]) + ","
    lines[k + 1] = ", ".join(swapped[9:])
    (tmp_path / "w.inp").write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=r"w\.inp:\d+: C3D15 element 2 has a Jacobian <= 0"):
        run_job("w", tmp_path, progress=False)


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_frd_stresses_match_ccx(tmp_path):
    """``*EL FILE S, E, ME, ENER`` of the NLGEOM block: ccx's nodal values (its extrapolation of
    the 9 points, averaged at shared nodes) to the .frd's 6 printed digits, and its ``*EL PRINT``
    of the four at the 9 points to the .dat's digits; serial and on 2 processes.
    """
    ccx_dat, ours_dat = _run(tmp_path, "wedge_block_frd", MPI.COMM_WORLD)
    worst = _check(ccx_dat, ours_dat, free_rf=1e-4)
    assert set(worst) == {"U", "RF", "S", "E", "ME", "ENER"}
    assert all(value < 1e-6 for value in worst.values()), worst
    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path), root=0))
    if comm.rank != 0:
        return
    theirs = read_frd(DATA / "wedge_block_frd.frd.ref")
    ours = read_frd(root / "wedge_block_frd.frd")
    names = ("STRESS", "TOSTRAIN", "MESTRAIN", "ENER")
    a = [b for b in theirs.blocks if b.name in names]
    b = [b for b in ours.blocks if b.name in names]
    assert [(x.name, x.time) for x in a] == pytest.approx([(y.name, y.time) for y in b])
    assert len(a) == 16  # S, E, ME and ENER of 4 increments
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x.nodes, y.nodes)
        assert np.abs(x.values - y.values).max() < 1e-5 * np.abs(x.values).max(), x.name


def test_c3d15_extrapolation_is_ccx_table():
    """ccx 2.20's C3D15 extrapolation (fitted to its .frd of one element under random nodal
    displacements, docs/method.md §34): linear in the triangle, least squares along the axis."""
    table = ELEMENT_TYPES["C3D15"].extrapolation
    np.testing.assert_allclose(table[0, [0, 3, 6]], [1.63138, 0.55556, -0.52027], atol=1e-5)
    np.testing.assert_allclose(table[0, [1, 4, 7]], [-0.32628, -0.11111, 0.10405], atol=1e-5)
    np.testing.assert_allclose(table[12], np.tile([5 / 9, -1 / 9, -1 / 9], 3), atol=1e-12)
    np.testing.assert_allclose(table[6], (table[0] + table[1]) / 2, atol=1e-12)  # midsides


def _eigenvalues(path: Path) -> np.ndarray:
    """The rows of ccx's eigenvalue table (mode, eigenvalue, rad/time, cycles/time, imaginary)."""
    lines = path.read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if "E I G E N V A L U E" in line)
    rows = []
    for line in lines[start + 1 :]:
        fields = line.split()
        if len(fields) == 5 and fields[0].isdigit():
            rows.append([float(f) for f in fields])
        elif rows:
            break
    return np.array(rows)


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_frequencies_match_ccx(tmp_path):
    """*FREQUENCY: the 6 eigenvalues of the block equal ccx's printed digits (the mass at ccx's
    9 points is ccx's), serial and on 2 processes."""
    comm = MPI.COMM_WORLD
    _run(tmp_path, "wedge_block_frequency", comm)
    root = Path(comm.bcast(str(tmp_path), root=0))
    if comm.rank != 0:
        return
    theirs = _eigenvalues(DATA / "wedge_block_frequency.dat.ref")
    ours = _eigenvalues(root / "wedge_block_frequency.dat")
    assert theirs.shape == (6, 5)
    np.testing.assert_allclose(ours, theirs, rtol=1e-6)
