"""``*TIE`` in the deck runner against ccx 2.20 (docs/method.md §19): generated decks of two
non-matching C3D8 blocks tied and of a cyclic sector, and CalculiX's own scheibe2n2f.

Every comparison runs ccx (on rank 0) and the deck runner (serially, or on all processes for the
``mpi`` tests) in the same test.
"""

from __future__ import annotations

import dataclasses
import gzip
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.decks import CCX_TESTS
from helpers.tie_decks import sector_deck, tied_blocks_deck, tied_quadratic_blocks_deck

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.model.ties import tie_constraints

COMM = MPI.COMM_WORLD
needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="needs ccx")

TIE = "*TIE, NAME=T1\nSLAVE, MASTER"
CASES = {
    "face_slave": {},
    "node_slave_adjusted": {"slave_nodal": True, "gap": 0.003},  # within ccx's 0.00356
    "no_adjust": {"gap": 0.003, "tie": "*TIE, NAME=T1, ADJUST=NO\nSLAVE, MASTER"},
    "tolerance": {"gap": 0.01, "tie": "*TIE, NAME=T1, POSITION TOLERANCE=0.02\nSLAVE, MASTER"},
    "nlgeom": {"nlgeom": True, "gap": 0.002},
}


def _both(tmp_path: Path, name: str, text: str) -> tuple[Path, Path]:
    """Run ``text`` with ccx (rank 0) and the deck runner (every process): the two directories."""
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    if COMM.rank == 0:
        for directory in (ccx_dir, ntf_dir):
            directory.mkdir(parents=True, exist_ok=True)
            (directory / f"{name}.inp").write_text(text)
        run_ccx(ccx_dir, name, timeout=120)
    ntf_dir = Path(COMM.bcast(str(ntf_dir)))
    COMM.barrier()
    assert run_job(name, ntf_dir, progress=False, comm=COMM).completed
    return ccx_dir, ntf_dir


def _dat_difference(ccx_dir: Path, ntf_dir: Path, name: str) -> float:
    """Largest difference of the ``.dat`` blocks relative to ccx's largest value (rank 0)."""
    theirs, ours = read_dat(ccx_dir / f"{name}.dat"), read_dat(ntf_dir / f"{name}.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    worst = 0.0
    for mine, reference in zip(ours, theirs):
        np.testing.assert_array_equal(mine.labels, reference.labels)
        scale = np.abs(reference.values).max()
        assert scale > 0
        worst = max(worst, float(np.abs(mine.values - reference.values).max() / scale))
    return worst


@needs_ccx
@pytest.mark.serial
@pytest.mark.parametrize("case", sorted(CASES))
def test_tied_blocks_match_ccx(tmp_path, case):
    ccx_dir, ntf_dir = _both(tmp_path, "tied", tied_blocks_deck(**CASES[case]))
    assert _dat_difference(ccx_dir, ntf_dir, "tied") < 1e-6


@needs_ccx
@pytest.mark.serial
@pytest.mark.parametrize("element", ["C3D20", "C3D20R"])
@pytest.mark.parametrize("nodal", [False, True])
def test_tied_quadratic_blocks_match_ccx(tmp_path, element, nodal):
    """quad8 master faces; the slave's midside nodes are tied too."""
    ccx_dir, ntf_dir = _both(
        tmp_path, "tied", tied_quadratic_blocks_deck(element, slave_nodal=nodal)
    )
    assert _dat_difference(ccx_dir, ntf_dir, "tied") < 1e-6


@needs_ccx
@pytest.mark.mpi
def test_tied_blocks_and_cyclic_sector_match_ccx_on_all_processes(tmp_path):
    root = Path(COMM.bcast(str(tmp_path)))
    for name, text in (("tied", tied_blocks_deck()), ("sector", sector_deck())):
        ccx_dir, ntf_dir = _both(root / name, name, text)
        if COMM.rank == 0:
            assert _dat_difference(ccx_dir, ntf_dir, name) < 1e-6


@needs_ccx
@pytest.mark.serial
def test_cyclic_sector_matches_ccx_and_turns_the_displacement(tmp_path):
    ccx_dir, ntf_dir = _both(tmp_path, "sector", sector_deck())
    assert _dat_difference(ccx_dir, ntf_dir, "sector") < 1e-6
    # axisymmetric expansion: the dependent face's displacement is the independent face's, turned
    deck = read_deck(ntf_dir / "sector.inp")
    (block,) = read_dat(ntf_dir / "sector.dat")
    u = dict(zip(block.labels.tolist(), block.values))
    angle = np.radians(30.0)
    turn = np.array(
        [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    )
    for master, slave in zip(deck.nsets["MASTERN"], deck.nsets["SLAVEN"]):
        np.testing.assert_allclose(u[int(slave)], turn @ u[int(master)], atol=2e-10)
    assert np.abs(block.values).max() > 1e-4


def test_tie_rows_and_adjust_on_the_deck(tmp_path):
    """Every slave node of the generated deck is tied (3 rows), ADJUST moves nodes within the
    tolerance, and a cyclic tie that does not match names the node."""
    path = tmp_path / "tied.inp"
    path.write_text(tied_blocks_deck(gap=0.003, slave_nodal=True))
    deck = read_deck(path)
    adjusted, (block,) = tie_constraints(deck, np.ones(deck.node_ids.size, dtype=bool))
    assert len(block) == 3 * 16 and block.nodes.shape[1] == 5 and block.drop_prescribed
    slaves = deck.node_index(deck.nsets["UBOT"])
    np.testing.assert_allclose(deck.node_coords[slaves, 2], 0.003)
    np.testing.assert_allclose(adjusted.node_coords[slaves, 2], 0.0, atol=1e-15)
    np.testing.assert_allclose(block.coefficients.sum(axis=1), 0.0, atol=1e-14)
    # far: not tied (with ccx's warning), nothing moved
    path.write_text(tied_blocks_deck(gap=0.004))
    deck = read_deck(path)
    adjusted, blocks = tie_constraints(deck, np.ones(deck.node_ids.size, dtype=bool))
    assert blocks == [] and np.array_equal(adjusted.node_coords, deck.node_coords)
    # cyclic faces: a slave node off its master's radius, a wrong sector angle
    path.write_text(sector_deck())
    deck = read_deck(path)
    coords = deck.node_coords.copy()
    slave = deck.node_index(deck.nsets["SLAVEN"][:1])
    coords[slave] *= 1.01
    meshed = np.ones(deck.node_ids.size, dtype=bool)
    with pytest.raises(NotImplementedError, match=r"1 slave node\(s\) match no master node .* "
                       r"\(e\.g\. node 17\)"):  # fmt: skip
        tie_constraints(dataclasses.replace(deck, node_coords=coords), meshed)
    path.write_text(sector_deck(angle=29.0))
    deck = read_deck(path)
    with pytest.raises(ValueError, match=r"sector angle of the geometry, 29 degrees, differs"):
        tie_constraints(deck, meshed)


SCHEIBE = [CCX_TESTS / f"scheibe2n2f.{end}" for end in ("inp.gz", "inp")]


@pytest.mark.mpi
@pytest.mark.skipif(
    shutil.which("ccx") is None or not any(p.is_file() for p in SCHEIBE),
    reason="needs ccx and the package calculix-ccx-test",
)
def test_scheibe2n2f_matches_ccx(tmp_path):
    """CalculiX's cyclic-symmetry contact deck (two rings, two cyclic ties, NLGEOM): its only
    outputs are the .frd's DISP and CONTACT blocks (serially and on all processes)."""
    source = next(p for p in SCHEIBE if p.is_file())
    opener = gzip.open if source.suffix == ".gz" else open
    with opener(source, "rt", encoding="latin-1") as stream:
        text = stream.read()
    ccx_dir, ntf_dir = _both(Path(COMM.bcast(str(tmp_path))), "scheibe2n2f", text)
    if COMM.rank:
        return
    theirs, ours = read_frd(ccx_dir / "scheibe2n2f.frd"), read_frd(ntf_dir / "scheibe2n2f.frd")
    for name in ("DISP", "CONTACT"):
        (mine,), (reference,) = ours.blocks_named(name), theirs.blocks_named(name)
        np.testing.assert_array_equal(mine.nodes, reference.nodes)
        scale = np.abs(reference.values).max(axis=0)
        difference = np.abs(mine.values - reference.values).max(axis=0)
        assert np.all(difference <= 1e-5 * np.maximum(scale, scale.max())), name
