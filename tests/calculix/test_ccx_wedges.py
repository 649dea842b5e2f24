"""C3D6 wedges read as C3D8 with one collapsed edge, and surfaces named twice (docs/method.md §30).

A 2 x 2 x 2 block of hexahedra, each split into two wedges, sheared and compressed: the runner
integrates the wedges with ccx's two-point C3D6 rule and prints the displacements and reactions of
ccx 2.20's C3D6 block (to its printed digits); the same block written as collapsed C3D8 (eight
points) differs by a few percent.
ccx's metalforming deck (28 wedges, surfaces named twice) against ccx 2.20.
"""

from __future__ import annotations

import functools
import gzip
import logging
import shutil
import tempfile
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import run_ccx_and_ours
from helpers.decks import UNIT_C3D8
from helpers.wedge_decks import wedge_block as _block

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, face_nodes, read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.fem.collapsed_wedges import check_vertices_joined
from dolfinx_ntf.kernels.collapsed_wedges import unmatched_neighbours

# ccx's wedge faces S1..S5 (manual): 1-2-3, 4-5-6, 1-2-5-4, 2-3-6-5, 3-1-4-6
WEDGE_FACES = ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5))


def test_wedges_become_collapsed_hexahedra(tmp_path: Path) -> None:
    text, wedges = _block()
    path = tmp_path / "w.inp"
    path.write_text(text)
    deck = read_deck(path)
    block = deck.elements["C3D8"]
    assert deck.wedges.tolist() == list(range(1, len(wedges) + 1))
    for e, wedge in enumerate(wedges, start=1):
        row = block.connectivity[block.ids.tolist().index(e)]
        assert sorted(set(row.tolist())) == sorted(wedge)  # the wedge's nodes, one edge twice
        assert row[2] == row[3] and row[6] == row[7]
        # turned (cyclically) but in ccx's order: triangle below triangle
        assert set(row[:4].tolist()) == set(wedge[:3]) and set(row[4:].tolist()) == set(wedge[3:])
    collapsed = {frozenset(row[[2, 6]].tolist()) for row in block.connectivity}
    assert len(collapsed) == len(wedges)  # no edge collapsed twice (dolfinx cannot mesh that)
    for k, element in zip(range(1, 6), (1, 3, 5, 6, 8)):  # each label names the wedge's face
        nodes = set(face_nodes(deck, f"S{k}")[0].tolist())
        assert nodes == {wedges[element - 1][i] for i in WEDGE_FACES[k - 1]}, k


def test_wedges_refused_with_a_clear_error(tmp_path: Path) -> None:
    text, _ = _block()
    path = tmp_path / "w.inp"
    mirrored = text.replace("\n1, 1, 2, 5, 10, 11, 14\n", "\n1, 2, 1, 5, 11, 10, 14\n")
    assert mirrored != text
    path.write_text(mirrored)
    with pytest.raises(DeckError, match="C3D6 element 1 has a Jacobian <= 0"):
        read_deck(path)
    path.write_text(text.replace("\n1, 1, 2, 5, 10, 11, 14\n", "\n1, 1, 2, 5, 10, 11, 5\n"))
    with pytest.raises(DeckError, match="element 1 repeats a node"):
        read_deck(path)
    path.write_text(text.replace("5, S5", "5, S6").replace("8, S5", "8, S6"))
    with pytest.raises(DeckError, match="face S6 of a C3D6 element"):
        read_deck(path)
    # one layer of 3 x 3 split hexahedra: 18 wedges, 16 vertical edges to collapse
    path.write_text(_block(n=3, layers=1)[0])
    with pytest.raises(DeckError, match="collapsed edges apart"):
        read_deck(path)


@pytest.mark.parametrize("request_card", ["*EL FILE\nS, HFL", "*EL FILE\nHFL"])
def test_element_outputs_of_wedges_refused(tmp_path: Path, request_card: str) -> None:
    text = _block(surfaces=False)[0].replace("*END STEP", f"{request_card}\n*END STEP")
    (tmp_path / "w.inp").write_text(text)
    with pytest.raises(NotImplementedError, match="of C3D6 element 1 is not supported"):
        run_job("w", tmp_path, comm=MPI.COMM_SELF, progress=False)


TWINS = (
    UNIT_C3D8
    + """*SURFACE, NAME=TOP, TYPE=NODE
5, 6
*SURFACE, NAME=TOP
1, S2
*SURFACE, NAME=BOTTOM
1, S1
*SURFACE, NAME=BOTTOM, TYPE=NODE
1, 2, 3
*MATERIAL, NAME=EL
*ELASTIC
1000., 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=EL
*SURFACE INTERACTION, NAME=SI
*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR
1.E5
*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE
TOP, BOTTOM
BOTTOM, TOP
*STEP
*STATIC
*END STEP
"""
)


def test_node_and_element_surface_of_one_name(tmp_path: Path) -> None:
    path = tmp_path / "t.inp"
    path.write_text(TWINS)
    deck = read_deck(path)
    first, second = deck.contact_pairs
    assert (first.slave, first.master) == ("TOP#NODES", "BOTTOM")
    assert (second.slave, second.master) == ("BOTTOM#NODES", "TOP")
    assert deck.surfaces["TOP#NODES"].type == "NODE" and deck.surfaces["TOP"].type == "ELEMENT"
    assert deck.surfaces["TOP#NODES"].nodes.tolist() == [5, 6]
    assert deck.surfaces["BOTTOM#NODES"].nodes.tolist() == [1, 2, 3]
    assert deck.surfaces["BOTTOM"].faces.tolist() == [1]
    path.write_text(TWINS.replace("*MATERIAL", "*SURFACE, NAME=TOP\n1, S3\n*MATERIAL"))
    with pytest.raises(DeckError, match="surface TOP is defined twice"):
        read_deck(path)


def _run_ours(directory: Path, job: str) -> None:
    logger = logging.getLogger("dolfinx_ntf")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        result = run_job(job, directory, comm=MPI.COMM_SELF, progress=False)
    finally:
        logger.setLevel(level)
    assert result.completed


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.parametrize(
    ("nlgeom", "mixed"),
    [(False, False), (True, False), (False, True)],
    ids=["small", "nlgeom", "mixed"],
)
def test_wedge_block_against_ccx(tmp_path: Path, nlgeom: bool, mixed: bool) -> None:
    """Wedges (``mixed``: beside C3D8) against ccx's C3D6 and its collapsed C3D8."""
    ours_dir, hex_dir, wedge_dir = (tmp_path / d for d in ("ntf", "hex", "wedge"))
    for d, element in ((ours_dir, "C3D6"), (hex_dir, "C3D8"), (wedge_dir, "C3D6")):
        d.mkdir()
        text = _block(element=element, surfaces=False, mixed=mixed)[0]
        (d / "w.inp").write_text(text.replace("*STEP\n", "*STEP, NLGEOM\n") if nlgeom else text)
    run_ccx(hex_dir, "w", timeout=120)
    run_ccx(wedge_dir, "w", timeout=120)
    _run_ours(ours_dir, "w")
    ours = read_dat(ours_dir / "w.dat")
    collapsed, wedge = read_dat(hex_dir / "w.dat"), read_dat(wedge_dir / "w.dat")
    assert [b.name for b in ours] == [b.name for b in collapsed] == ["U", "RF_TOTAL"]
    for a, b, c in zip(ours, collapsed, wedge):
        np.testing.assert_array_equal(a.labels, c.labels)
        scale = np.abs(c.values).max()
        # ccx's two-point C3D6 rule on the collapsed cells: ccx's C3D6 to its printed digits
        assert np.abs(a.values - c.values).max() <= 2e-6 * scale, a.name
        # ccx's collapsed C3D8 integrates with 8 points: measured 2.8e-2 (U) and 1.6e-2 (RF) here
        difference = np.abs(a.values - b.values).max() / scale
        assert 1e-3 < difference < 5e-2, (a.name, difference)


def _check_wedge_stresses(tmp_path: Path, nlgeom: bool, mixed: bool, comm: MPI.Comm) -> None:
    """``*EL PRINT`` S and E of the wedge block against ccx 2.20 (its printed digits)."""
    text, wedges = _block(surfaces=False, mixed=mixed)
    text = text.replace("*END STEP", "*EL PRINT, ELSET=EALL\nS, E\n*END STEP")
    if nlgeom:
        text = text.replace("*STEP\n", "*STEP, NLGEOM\n")
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", text, comm=comm)
    if comm.rank != 0:
        return
    ours, theirs = read_dat(ntf_dir / "w.dat"), read_dat(ccx_dir / "w.dat")
    assert [b.name for b in ours] == [b.name for b in theirs] == ["U", "RF_TOTAL", "S", "E"]
    points = np.bincount(theirs[2].labels[:, 0])[1:]
    assert points.tolist() == [2] * len(wedges) + [8] * (points.size - len(wedges))
    for a, b in zip(ours[2:], theirs[2:]):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(b.values).max()
        assert np.abs(a.values - b.values).max() <= 1e-6 * scale, a.name
        # the two points differ: their order is checked
        assert np.abs(b.values[0] - b.values[1]).max() > 1e-3 * scale


@pytest.mark.mpi
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.parametrize("nlgeom", [False, True], ids=["small", "nlgeom"])
def test_wedge_stresses_against_ccx(tmp_path: Path, nlgeom: bool) -> None:
    """``*EL PRINT`` S and E of the 16 wedges at ccx's two C3D6 points (docs/method.md §30.6).

    Two rows per wedge in ccx's point order: ccx 2.20's values to its printed digits, serial and
    on 2 processes.
    """
    _check_wedge_stresses(tmp_path, nlgeom, False, MPI.COMM_WORLD)


@pytest.mark.mpi
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
def test_mixed_wedge_stresses_against_ccx(tmp_path: Path) -> None:
    """S and E of wedges beside C3D8 (2 and 8 rows) to ccx 2.20's printed digits, serial and on
    several processes (whose cut dolfinx 0.5.2 left unjoined before docs/method.md §37)."""
    _check_wedge_stresses(tmp_path, False, True, MPI.COMM_WORLD)


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.parametrize(
    ("nlgeom", "tolerance"), [(False, 1e-6), (True, 1e-5)], ids=["small", "nlgeom"]
)
def test_plastic_wedge_stresses_against_ccx(tmp_path: Path, nlgeom: bool, tolerance: float) -> None:
    """S, E and PEEQ of plastic wedges (their laws' two points) beside plastic C3D8, 4 increments.

    Measured against ccx 2.20: its printed digits (difference 0); with NLGEOM 7.0e-6 of the largest
    value (as U and RF of this deck, ``test_plastic_wedges_against_ccx``). Serial: the mixed block.
    """
    text, wedges = _block(surfaces=False, mixed=True)
    text = text.replace("210000., 0.3\n", "210000., 0.3\n*PLASTIC\n300., 0.\n400., 0.1\n")
    text = text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")
    text = text.replace("*END STEP", "*EL PRINT, ELSET=EALL\nS, E, PEEQ\n*END STEP")
    if nlgeom:
        text = text.replace("*STEP\n", "*STEP, NLGEOM\n")
    ccx_dir, ntf_dir = run_ccx_and_ours(tmp_path, "w", text)
    ours, theirs = read_dat(ntf_dir / "w.dat"), read_dat(ccx_dir / "w.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    printed = [(a, b) for a, b in zip(ours, theirs) if a.name in ("S", "E", "PEEQ")]
    assert len(printed) == 12  # 3 keys at 4 increments
    for a, b in printed:
        np.testing.assert_array_equal(a.labels, b.labels)
        points = np.bincount(b.labels[:, 0])[1:]
        assert points.tolist() == [2] * len(wedges) + [8] * (points.size - len(wedges))
        scale = np.abs(b.values).max()
        assert np.abs(a.values - b.values).max() <= tolerance * scale, (a.name, a.time)
    peeq = printed[-1][1]
    assert np.abs(peeq.values[: 2 * len(wedges)]).min() > 0.0  # the wedges yielded


SUITE = Path("/usr/share/doc/calculix-ccx-test/examples/test")


def _metalforming(simplified: bool) -> str:
    """ccx's metalforming deck; ``simplified``: without friction, plasticity and NLGEOM."""
    text = gzip.decompress((SUITE / "metalforming.inp.gz").read_bytes()).decode("latin-1")
    if simplified:
        for old, new in (("*friction\n0.2,0.001\n", ""), ("*plastic\n50.0, 0.0\n100.0, 0.3\n", ""),
                         ("*step,nlgeom,inc=99999", "*step,inc=99999")):  # fmt: skip
            assert old in text
            text = text.replace(old, new)
    return text


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.skipif(not (SUITE / "metalforming.inp.gz").exists(), reason="no calculix-ccx-test")
@pytest.mark.parametrize("simplified", [True, False], ids=["elastic", "deck"])
def test_metalforming_against_ccx(tmp_path: Path, simplified: bool) -> None:
    """28 wedges on the axis of a cylindrical ``*TRANSFORM``, surfaces named twice.

    Elastic and frictionless, every block agrees to 2e-6 of its largest value. The deck itself
    (plastic sheet, friction, NLGEOM) converges in ccx's one increment with ccx's elastic first
    iteration (it stalled and cut back twice before, docs/method.md §33) and, with ccx's local
    directions on the axis (§33.3) and ccx's distance below which a node is on it (the punch's
    apex 21 lies 9.2e-16 off the axis, §33.6), agrees to 1e-5 in every column (measured: CDIS
    8.7e-7, CSTR 8.6e-7; 4.3e-4 and 8.9e-5 before §33.6). With the springs of the elastic first
    iteration at the increment start, as ccx's (§33.4, §33.5), it takes ccx's 5 iterations with
    ccx's number of springs in each (147, 146, 146, 147, 147: node 1020 open at iterations 2
    and 3) and agrees to 1e-6 (measured: 2.4e-7 in CDIS and CSTR).
    """
    ours_dir, ccx_dir = tmp_path / "ntf", tmp_path / "ccx"
    for d in (ours_dir, ccx_dir):
        d.mkdir()
        (d / "mf.inp").write_text(_metalforming(simplified))
    run_ccx(ccx_dir, "mf", timeout=300)
    _run_ours(ours_dir, "mf")
    theirs = read_dat(ccx_dir / "mf.dat")
    ours = {(b.name, b.time): b for b in read_dat(ours_dir / "mf.dat")}
    assert [b.name for b in theirs] == ["CDIS", "CSTR"]
    for block in theirs:
        mine = ours[(block.name, block.time)]
        np.testing.assert_array_equal(mine.labels, block.labels)  # 147 springs, node 1020 too
        scale = np.abs(block.values).max()
        difference = np.abs(mine.values - block.values).max() / scale
        assert difference <= (1e-5 if simplified else 1e-6), (block.name, difference)
    increments = [(r.step, r.increment, r.attempt) for r in read_sta(ours_dir / "mf.sta")]
    assert increments == [(r.step, r.increment, r.attempt) for r in read_sta(ccx_dir / "mf.sta")]
    assert increments == [(1, 1, 1)]  # no cut-back (the stall, docs/method.md §33)
    if not simplified:  # iterations and springs per iteration, from the .cvg files (§33.5)
        rows = [_cvg_springs(d / "mf.cvg") for d in (ours_dir, ccx_dir)]
        assert rows[0] == rows[1] == [147, 146, 146, 147, 147]


def _cvg_springs(path: Path) -> list[int]:
    """The contact-element column of a ``.cvg`` file, iteration by iteration."""
    rows = [line.split() for line in path.read_text().splitlines()]
    return [int(r[4]) for r in rows if len(r) == 9 and r[0].isdigit()]


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
def test_wedge_punch_against_ccx(tmp_path: Path) -> None:
    """A C3D8 block pressed by a punch of 12 wedges, the wedge triangles the master faces
    (docs/method.md §30.5): with ccx's two-point rule every printed block is ccx's C3D6 one
    (measured: U 1e-8, RF 1.8e-7, CDIS and CSTR to the printed digits; 1.7e-1 with 8 points)."""
    data = Path(__file__).parents[1] / "data" / "calculix" / "wedge_punch.inp"
    ours_dir, ccx_dir = tmp_path / "ntf", tmp_path / "ccx"
    for d in (ours_dir, ccx_dir):
        d.mkdir()
        shutil.copy(data, d / "wp.inp")
    run_ccx(ccx_dir, "wp", timeout=120)
    _run_ours(ours_dir, "wp")
    theirs = read_dat(ccx_dir / "wp.dat")
    ours = {(b.name, b.time): b for b in read_dat(ours_dir / "wp.dat")}
    assert {b.name for b in theirs} == {"U", "RF", "RF_TOTAL", "CDIS", "CSTR"}
    rf_scale = np.abs(next(b for b in theirs if b.name == "RF").values).max()
    for block in theirs:
        mine = ours[(block.name, block.time)]
        np.testing.assert_array_equal(mine.labels, block.labels)
        # the total reaction is a round-off zero in both: measured against the reactions
        scale = rf_scale if block.name == "RF_TOTAL" else np.abs(block.values).max()
        difference = np.abs(mine.values - block.values).max() / scale
        assert difference <= 1e-6, (block.name, difference)


@pytest.mark.serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.parametrize("nlgeom", [False, True], ids=["small", "nlgeom"])
def test_plastic_wedges_against_ccx(tmp_path: Path, nlgeom: bool) -> None:
    """Plastic wedges beside plastic C3D8, sheared far past yield in four increments: the wedges'
    laws at ccx's two C3D6 points (docs/method.md §30.5) give ccx's U and RF at every increment
    (measured: to the printed digits; 3.4e-6 with NLGEOM) and ccx's iterations."""
    text = _block(surfaces=False, mixed=True)[0]
    text = text.replace("210000., 0.3\n", "210000., 0.3\n*PLASTIC\n300., 0.\n400., 0.1\n")
    text = text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")
    if nlgeom:
        text = text.replace("*STEP\n", "*STEP, NLGEOM\n")
    ours_dir, ccx_dir = tmp_path / "ntf", tmp_path / "ccx"
    for d in (ours_dir, ccx_dir):
        d.mkdir()
        (d / "w.inp").write_text(text)
    run_ccx(ccx_dir, "w", timeout=120)
    _run_ours(ours_dir, "w")
    theirs, ours = read_dat(ccx_dir / "w.dat"), read_dat(ours_dir / "w.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    assert len(theirs) == 8  # U and RF at 4 increments
    for a, c in zip(ours, theirs):
        np.testing.assert_array_equal(a.labels, c.labels)
        difference = np.abs(a.values - c.values).max() / np.abs(c.values).max()
        assert difference <= 1e-5, (a.name, a.time, difference)
    iterations = [(r.increment, r.iterations) for r in read_sta(ours_dir / "w.sta")]
    assert iterations == [(r.increment, r.iterations) for r in read_sta(ccx_dir / "w.sta")]


@pytest.mark.mpi
def test_mixed_wedge_mesh_is_joined() -> None:
    """A mixed wedge and C3D8 block builds with one vertex per node on every process count.

    dolfinx 0.5.2 left this block's cut unjoined on 2 processes (36 vertices for 27 nodes, 33 on
    3; its displacements 63 % off ccx): the cells of the faces it does not match (a C3D8's
    quadrilateral on two wedge triangles) are now ghosts across the cut (docs/method.md §37).
    """
    from dolfinx_ntf.calculix.model import build_model

    comm = MPI.COMM_WORLD
    directory = Path(tempfile.mkdtemp())  # one per process
    path = directory / "w.inp"
    path.write_text(_block(surfaces=False, mixed=True)[0])
    try:
        model = build_model(read_deck(path), comm)
    finally:
        shutil.rmtree(directory, ignore_errors=True)
    assert model.mesh.topology.index_map(0).size_global == 27
    cells = model.mesh.topology.index_map(3)
    assert comm.allreduce(cells.size_local) == 12


def _mixed_cells() -> tuple[np.ndarray, np.ndarray]:
    """The mixed block's cells (dolfinx order) and points, as the deck runner makes them."""
    from dolfinx_ntf.calculix.model.mesh import element_block

    directory = Path(tempfile.mkdtemp())  # one per process
    try:
        (directory / "w.inp").write_text(_block(surfaces=False, mixed=True)[0])
        deck = read_deck(directory / "w.inp")
    finally:
        shutil.rmtree(directory, ignore_errors=True)
    block = element_block(deck)
    cells = deck.node_index(block.connectivity)[:, block.type.to_dolfinx]
    return cells.astype(np.int64), np.asarray(deck.node_coords, dtype=np.float64)


@pytest.mark.mpi
def test_unjoined_vertices_are_still_refused() -> None:
    """``check_vertices_joined`` stays the safety net: the block made without the ghosts across
    unmatched faces is refused exactly when dolfinx leaves vertices unjoined (0.5.2 on several
    processes: 36 vertices for 27 nodes on 2, 33 on 3; 0.9 and 0.11 join them)."""
    comm = MPI.COMM_WORLD
    cells, points = _mixed_cells()
    if comm.rank != 0:
        cells, points = np.zeros((0, 8), np.int64), np.zeros((0, 3))
    mesh = compat.create_mesh(comm, cells, points, compat.coordinate_element("hexahedron"))
    found = mesh.topology.index_map(0).size_global
    if not compat.JOINS_UNMATCHED_FACETS and comm.size > 1:
        assert found > 27  # what create_collapsed_mesh is for
    if found == 27:
        check_vertices_joined(mesh, cells)
    else:
        with pytest.raises(NotImplementedError, match=f"{found} vertices for 27 nodes"):
            check_vertices_joined(mesh, cells)


@pytest.mark.mpi
def test_chosen_partitions_through_every_unmatched_face_are_joined() -> None:
    """The C3D8 on process 0, the wedges dealt round-robin to the others (every unmatched face
    cut): one vertex per node, and the volume of the block. (This cut also crosses matched side
    faces, which join the vertices without the added ghosts too, measured; dolfinx's own
    partition is the one that needs them: ``test_unjoined_vertices_are_still_refused``.)"""
    comm = MPI.COMM_WORLD
    cells, points = _mixed_cells()
    pairs = unmatched_neighbours(cells)
    wedge = cells[:, 2] == cells[:, 3]  # collapsed on 2-3 and 6-7 (the reader's wedges)
    owners = np.where(wedge, 1 + np.arange(cells.shape[0]) % max(comm.size - 1, 1), 0)
    owners = np.minimum(owners, comm.size - 1).astype(np.int32)
    if comm.size > 1:
        assert np.all(owners[pairs[:, 0]] != owners[pairs[:, 1]])
    if comm.rank != 0:
        cells, points = np.zeros((0, 8), np.int64), np.zeros((0, 3))
        owners, pairs = owners[:0], pairs[:0]
    element = compat.coordinate_element("hexahedron")
    mesh = compat.create_mesh(comm, cells, points, element, owners, unmatched=pairs)
    assert mesh.topology.index_map(0).size_global == 27
    one = dolfinx.fem.form(dolfinx.fem.Constant(mesh, 1.0) * ufl.dx(domain=mesh))
    volume = comm.allreduce(dolfinx.fem.assemble_scalar(one))
    assert abs(volume - 1.0) < 1e-12


def _cut_mesh(deck, block, comm, carried=None, apart=False):
    """The deck runner's mesh with every unmatched face cut: each wedge on another process than
    the C3D8 its triangle lies on (the deck runner's own mesh on one process). ``apart``: every
    C3D8 on process 0 and every wedge on the last, so that a process holds no wedge."""
    from dolfinx_ntf.calculix.model.mesh import create_mesh

    if comm.size == 1:
        return create_mesh(deck, block, comm, carried)
    cells = deck.node_index(block.connectivity)[:, block.type.to_dolfinx].astype(np.int64)
    x = np.asarray(deck.node_coords, dtype=np.float64)
    pairs = unmatched_neighbours(cells)  # (C3D8, wedge): each wedge on one C3D8
    owners = np.arange(len(cells)) % comm.size
    hexahedron, wedge = pairs[:, 0], pairs[:, 1]
    owners[wedge] = (owners[hexahedron] + 1 + np.arange(len(wedge)) % (comm.size - 1)) % comm.size
    if apart:
        owners = np.where(np.isin(np.arange(len(cells)), wedge), comm.size - 1, 0)
    assert len(pairs) == 8 and np.all(owners[hexahedron] != owners[wedge])
    # apart: process 0 holds no wedge (the wedge outputs' collective compile, method §35)
    assert np.unique(owners[wedge]).size == (1 if apart else comm.size)
    if comm.rank != 0:
        cells, x, owners, pairs = cells[:0], x[:0], owners[:0], pairs[:0]
    element = compat.coordinate_element("hexahedron")
    mesh = compat.create_mesh(comm, cells, x, element, owners.astype(np.int32), unmatched=pairs)
    check_vertices_joined(mesh, cells)
    return mesh


@pytest.mark.mpi
@pytest.mark.parametrize("partition", ["dolfinx", "cut", "apart"])
@pytest.mark.parametrize("request_card", ["", "*EL PRINT, ELSET=EALL\nS, E\n"], ids=["U", "S"])
def test_mixed_wedge_block_gives_the_serial_files(
    request_card: str, partition: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The mixed block on all processes writes the serial run's files byte for byte.

    ``dolfinx``: its partition cuts C3D8 faces lying on wedge triangles (2 and 3 processes: the
    cut through the middle layer, unjoined without the ghosts of docs/method.md §37); ``cut``: a
    chosen partition cuts all 8 of them (and matched faces too, which join its vertices anyway);
    ``apart``: the C3D8 on process 0, the wedges on the last (process 0 holds no wedge, and still
    takes part in the wedge outputs' collective compilation, docs/method.md §35).
    """
    from dolfinx_ntf.calculix.model import calculix_model as model_module

    if partition != "dolfinx":
        cut = functools.partial(_cut_mesh, apart=partition == "apart")
        monkeypatch.setattr(model_module, "create_mesh", cut)
    from helpers.decks import first_differing_file, run_serial_and_parallel

    comm = MPI.COMM_WORLD
    directory = comm.bcast(tempfile.mkdtemp() if comm.rank == 0 else None, root=0)
    path = Path(directory) / "mixed.inp"
    try:
        if comm.rank == 0:
            text = _block(surfaces=False, mixed=True)[0]
            path.write_text(text.replace("*END STEP", request_card + "*END STEP"))
        comm.barrier()
        serial, parallel, serial_dir = run_serial_and_parallel(path)
        u = comm.bcast(serial.last.displacement if comm.rank == 0 else None, root=0)
        assert np.abs(u).max() > 0
        assert np.abs(parallel.last.displacement - u).max() <= 1e-10 * np.abs(u).max()
        files = first_differing_file(path, serial_dir) if comm.rank == 0 else None
        assert comm.bcast(files, root=0) is None, files
    finally:
        comm.barrier()
        if comm.rank == 0:
            shutil.rmtree(directory, ignore_errors=True)
