"""C3D8 beside C3D20/C3D20R, GRAV and *TIME POINTS in the deck runner, against ccx 2.20.

docs/method.md §27 (1 and 2 processes). The C3D8 cells are 20-node cells whose midside nodes
are fixed to their edges' means; their integration points stay C3D8's 2x2x2 (measured: with
C3D20's 3x3x3 on the distorted cube instead, U differs from ccx by 8.7e-4 of its largest value,
CSTR by 1.7e-4), and the cube's bottom faces are quad4 slave faces (quad8's corner weight 1/100
instead of 1/4 would give the corners 1/25 of their spring area). The decks are in
``tests/data/calculix/mixed/mixed_deck.py``.
"""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from mixed_deck import cube_on_floor_deck, falling_cube_deck, spinning_cube_deck

from dolfinx_ntf.calculix.ccx import read_sta, run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.model import build_model
from dolfinx_ntf.calculix.model.mixed import mixed_hexahedra

COMM = MPI.COMM_WORLD
HAS_CCX = shutil.which("ccx") is not None
needs_ccx = pytest.mark.skipif(not HAS_CCX, reason="CalculiX ccx is not installed")
BALL = Path("/usr/share/doc/calculix-ccx-test/examples/test/ball.inp.gz")


def _run_both(root: Path, job: str, text: str) -> tuple[Path, Path]:
    """Write ``text`` into ``root/ccx`` and ``root/ntf``, run ccx in the first (rank 0)."""
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if COMM.rank == 0:
        for directory in (ccx_dir, ntf_dir):
            directory.mkdir()
            (directory / f"{job}.inp").write_text(text)
        run_ccx(ccx_dir, job, timeout=120)
    COMM.barrier()
    return ccx_dir, ntf_dir


def _compare(ccx_dat: Path, ntf_dat: Path, tolerance: float) -> list:
    """Every ccx block has ours (same name, time, rows) within ``tolerance`` of its largest."""
    ccx, ntf = read_dat(ccx_dat), read_dat(ntf_dat)
    assert [(b.name, b.time) for b in ccx] == [(b.name, b.time) for b in ntf] and ccx
    for a, b in zip(ccx, ntf):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = max(np.abs(a.values).max(), 1e-300)
        assert np.abs(a.values - b.values).max() <= tolerance * scale, (a.name, a.time)
    return ntf


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("floor", ["S8", "C3D20R"])
def test_c3d8_cube_on_quadratic_floor_matches_ccx(tmp_path, floor):
    """A distorted C3D8 cube pressed onto a C3D20 (expanded S8) or C3D20R floor: 1e-6."""
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, "mixed", cube_on_floor_deck(floor))
    assert run_job("mixed", ntf_dir, comm=COMM, progress=False).completed
    if COMM.rank != 0:
        return
    ntf = _compare(ccx_dir / "mixed.dat", ntf_dir / "mixed.dat", 1e-6)
    pressure = next(b for b in ntf if b.name == "CSTR").values[:, 0]
    assert pressure.size == 4 and np.all(pressure > 0.1)  # the four corners press


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_falling_cube_time_points_match_ccx(tmp_path):
    """GRAV, initial velocity, NLGEOM and *TIME POINTS: ccx's increments and free fall."""
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, "fall", falling_cube_deck())
    assert run_job("fall", ntf_dir, comm=COMM, progress=False).completed
    if COMM.rank != 0:
        return
    ntf = _compare(ccx_dir / "fall.dat", ntf_dir / "fall.dat", 1e-6)
    assert [b.time for b in ntf] == pytest.approx([2.5e-4, 5e-4, 7.5e-4, 1e-3])
    for block in ntf:  # free fall: (v t, 0, -g t^2 / 2)
        t = block.time
        np.testing.assert_allclose(block.values[:, 0], 100.0 * t, rtol=1e-6)
        np.testing.assert_allclose(block.values[:, 2], -0.5 * 9810.0 * t**2, rtol=1e-6)
    # the increments of 3e-4 are shortened to end on the time points, as in ccx
    ours, theirs = read_sta(ntf_dir / "fall.sta"), read_sta(ccx_dir / "fall.sta")
    assert len(ours) == len(theirs) == 4
    np.testing.assert_allclose([r.step_time for r in ours], [r.step_time for r in theirs])


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("floor", [True, False])
def test_spinning_cube_mass_matches_ccx(tmp_path, floor):
    """ccx's C3D8 mass is integrated at the 2x2x2 Gauss points, alone and beside C3D20.

    Measured: 9.6e-7 of the largest displacement (printed digits: 1e-7); with the exactly
    integrated mass 1.6e-4.
    """
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, "spin", spinning_cube_deck(floor))
    assert run_job("spin", ntf_dir, comm=COMM, progress=False).completed
    if COMM.rank != 0:
        return
    ntf = _compare(ccx_dir / "spin.dat", ntf_dir / "spin.dat", 2e-6)
    assert len(ntf) == 10 and np.abs(ntf[-1].values).max() > 0.05  # it moved


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.skipif(not BALL.exists(), reason="calculix-ccx-test is not installed")
def test_ball_deck_matches_ccx(tmp_path):
    """CalculiX's own ball deck (C3D8 ball, S8 floor, GRAV, time points): ccx's U to 1e-6."""
    text = gzip.decompress(BALL.read_bytes()).decode("latin-1")
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, "ball", text)
    assert run_job("ball", ntf_dir, comm=COMM, progress=False).completed
    if COMM.rank != 0:
        return
    ntf = _compare(ccx_dir / "ball.dat", ntf_dir / "ball.dat", 1e-6)
    (block,) = ntf
    assert block.values.shape == (1017, 3)  # the ball's nodes, no added midside node
    np.testing.assert_allclose(block.values[:, 2], -0.5 * 9810.0 * 1e-3**2, rtol=1e-6)


def test_mixed_hexahedra_adds_midside_nodes(tmp_path):
    """Each C3D8 edge gets one midside node at its midpoint; shared edges once."""
    text = cube_on_floor_deck("C3D20R").replace(
        "1, 1, 2, 3, 4, 5, 6, 7, 8", "1, 1, 2, 3, 4, 5, 6, 7, 8\n2, 5, 6, 7, 8, 9, 10, 11, 12"
    )
    text = text.replace("*ELEMENT, TYPE=C3D8", "9, 0., 0., 2.\n10, 1., 0., 2.\n"
                        "11, 1., 1., 2.\n12, 0., 1., 2.\n*ELEMENT, TYPE=C3D8")  # fmt: skip
    path = tmp_path / "two.inp"
    path.write_text(text)
    deck, mixed = mixed_hexahedra(read_deck(path))
    block = deck.elements["C3D20R"]
    assert block.ids.tolist() == [1, 2, 101] and mixed.linear.tolist() == [True, True, False]
    assert mixed.added_nodes.size == 20  # 12 + 12 edges, 4 shared
    assert mixed.added_nodes.min() > 120
    rows = deck.node_index(block.connectivity[:2])
    x = deck.node_coords[rows]  # (2, 20, 3)
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
             (2, 6), (3, 7)]  # fmt: skip
    for k, (a, b) in enumerate(edges):
        np.testing.assert_allclose(x[:, 8 + k], 0.5 * (x[:, a] + x[:, b]))


def test_mixed_hexahedra_refuses_shared_edges(tmp_path):
    """A C3D8 edge that is also a C3D20R edge is refused, naming its nodes."""
    text = cube_on_floor_deck("C3D20R").replace(
        "*ELEMENT, TYPE=C3D8, ELSET=ECUBE\n1, 1, 2, 3, 4, 5, 6, 7, 8",
        "*ELEMENT, TYPE=C3D8, ELSET=ECUBE\n1, 1, 2, 3, 4, 105, 106, 107, 108",
    )
    path = tmp_path / "shared.inp"
    path.write_text(text)
    with pytest.raises(NotImplementedError, match=r"the edge between nodes 105 and 106"):
        mixed_hexahedra(read_deck(path))


def test_mixed_deck_refuses_element_output(tmp_path):
    """*EL PRINT in a mixed deck is refused, naming its line (not measured against ccx)."""
    text = cube_on_floor_deck("S8").replace(
        "*CONTACT PRINT", "*EL PRINT, ELSET=ECUBE\nS\n*CONTACT PRINT"
    )
    path = tmp_path / "elprint.inp"
    path.write_text(text)
    line = text.split("\n").index("*EL PRINT, ELSET=ECUBE") + 1
    with pytest.raises(NotImplementedError, match=rf"elprint.inp:{line}: \*EL PRINT in a deck"):
        build_model(read_deck(path), MPI.COMM_SELF)
