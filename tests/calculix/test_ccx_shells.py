"""S8 shells expanded into C3D20 bricks in the deck runner, against ccx 2.20 (docs/method.md §24).

The decks (``tests/data/calculix/shells/shell_deck.py``) run in ccx 2.20 and in the deck
runner. The expanded nodes and bricks equal those of ccx's ``.frd`` (``OUTPUT=3D``; coordinates
within its 5 printed digits); the ``*NODE PRINT`` displacements of the shell nodes (ccx's
combination of the expanded nodes) and the contact rows of a cube pressed onto a fully fixed S8
floor agree with ccx's within 1e-6 of the block's largest value (measured: equal to the printed
digits but for the exponential law, 4e-6 on CSTR, and NLGEOM, 2e-7).
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from shell_deck import (
    PLATE_VARIANTS,
    block_deck,
    cylinder_deck,
    flying_block_deck,
    plate_deck,
    s4_block_deck,
    s4_plate_deck,
    write_deck,
)

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.shell_expansion import ShellExpansion, expand_shells

COMM = MPI.COMM_WORLD
HAS_CCX = shutil.which("ccx") is not None
needs_ccx = pytest.mark.skipif(not HAS_CCX, reason="CalculiX ccx is not installed")

DECKS = {
    **{f"plate-{v}": (lambda v=v: plate_deck(v)) for v in PLATE_VARIANTS},
    "cylinder": cylinder_deck,
    "block-linear": lambda: block_deck("LINEAR"),
    "block-exponential": lambda: block_deck("EXPONENTIAL"),
    "s4-block": s4_block_deck,  # a C3D8I cube on a fixed S4 floor (S4 -> C3D8I)
}


def _run_both(root: Path, text: str) -> tuple[Path, Path]:
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if COMM.rank == 0:
        ccx_dir.mkdir()
        ntf_dir.mkdir()
        write_deck(ccx_dir, "shell", text)
        write_deck(ntf_dir, "shell", text)
        run_ccx(ccx_dir, "shell", timeout=120)
    COMM.barrier()
    return ccx_dir, ntf_dir


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("name", list(DECKS))
def test_shell_deck_matches_ccx(tmp_path, name):
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, DECKS[name]())
    result = run_job("shell", ntf_dir, comm=COMM, progress=False)
    assert result.completed
    if COMM.rank != 0:
        return
    ccx = read_dat(ccx_dir / "shell.dat")
    ntf = [b for b in read_dat(ntf_dir / "shell.dat") if b.time == pytest.approx(1.0)]
    assert [b.name for b in ccx] == [b.name for b in ntf] and ccx
    for a, b in zip(ccx, ntf):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(a.values).max()
        assert scale > 0
        tolerance = 5e-6 if name == "block-exponential" else 1e-6
        assert np.abs(a.values - b.values).max() <= tolerance * scale, (name, a.name)
    if name.startswith("block"):  # the cube's bottom presses into the floor
        pressure = next(b for b in ntf if b.name == "CSTR").values[:, 0]
        assert np.all(pressure > 0.1)


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("variant", ["clamped", "supported"])
def test_shell_frd_matches_ccx(tmp_path, variant):
    """The ``.frd``: the bricks' nodes (no shell nodes, no unused middle nodes), DISP and FORC."""
    root = Path(COMM.bcast(str(tmp_path), root=0))
    text = plate_deck(variant).replace("*END STEP", "*NODE FILE\nU, RF\n*END STEP")
    ccx_dir, ntf_dir = _run_both(root, text)
    assert run_job("shell", ntf_dir, comm=COMM, progress=False).completed
    if COMM.rank != 0:
        return
    ccx, ntf = read_frd(ccx_dir / "shell.frd"), read_frd(ntf_dir / "shell.frd")
    assert len(np.asarray(ccx.node_ids)) == 32  # 13 shell nodes: 8 corners x 3, 5 midside x 2
    np.testing.assert_array_equal(np.asarray(ccx.node_ids), np.asarray(ntf.node_ids))
    np.testing.assert_allclose(np.asarray(ntf.node_coords), np.asarray(ccx.node_coords), atol=5e-6)
    np.testing.assert_array_equal(np.asarray(ccx.element_nodes), np.asarray(ntf.element_nodes))
    assert [b.name for b in ccx.blocks] == [b.name for b in ntf.blocks] == ["DISP", "FORC"]
    for a, b in zip(ccx.blocks, ntf.blocks):
        np.testing.assert_array_equal(a.nodes, b.nodes)
        assert np.abs(a.values - b.values).max() <= 1e-6 * np.abs(a.values).max(), a.name


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_flying_c3d20_block_matches_ccx(tmp_path):
    """A C3D20 cube's initial velocity in a *DYNAMIC step, next to a fixed S8 floor.

    The velocity of C3D20's face and cell centres follows the nodes' (before, they were left at
    zero and the cube flew 0.26 of ``v t``).
    """
    root = Path(COMM.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = _run_both(root, flying_block_deck())
    result = run_job("shell", ntf_dir, comm=COMM, progress=False)
    assert result.completed
    if COMM.rank != 0:
        return
    ccx = read_dat(ccx_dir / "shell.dat")
    ntf = {b.time: b for b in read_dat(ntf_dir / "shell.dat")}
    assert len(ccx) == 8
    for a in ccx:
        b = ntf[a.time]
        np.testing.assert_allclose(a.values[:, 2], -2.0 * a.time, rtol=1e-6)
        assert np.abs(a.values - b.values).max() <= 1e-9 * np.abs(a.values).max()


@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("which", ["plate", "cylinder", "s4"])
def test_expanded_nodes_match_ccx_frd(tmp_path, which):
    """The bricks' nodes and numbering as ccx 2.20 writes them with ``OUTPUT=3D``."""
    decks = {
        "plate": lambda: plate_deck("hinged", file_output=True),
        "cylinder": lambda: cylinder_deck(file_output=True),
        "s4": s4_plate_deck,  # a warped element: node 6 lifted 0.5
    }
    write_deck(tmp_path, "shell", decks[which]())
    run_ccx(tmp_path, "shell", timeout=120)
    frd = read_frd(tmp_path / "shell.frd")
    deck = read_deck(tmp_path / "shell.inp")
    (block,) = deck.elements.values()
    assert block.type.name == ("C3D8I" if which == "s4" else "C3D20")
    np.testing.assert_array_equal(
        np.asarray(frd.element_nodes), block.connectivity[:, block.type.frd_nodes]
    )
    used = np.unique(block.connectivity)
    frd_ids = np.asarray(frd.node_ids)
    ours = deck.node_coords[deck.node_index(used)]
    theirs = np.asarray(frd.node_coords)[np.searchsorted(frd_ids, used)]
    assert np.abs(ours - theirs).max() <= 5e-6 * max(1.0, np.abs(theirs).max())


#: An S8 element of 2 x 1 in the plane z = 0: corners, then midside nodes.
FLAT_S8 = np.array(
    [[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [1, 0, 0], [2, 0.5, 0], [1, 1, 0], [0, 0.5, 0]],
    float,
)


def _flat_s8(offset: float = 0.0, thickness: float = 0.2):
    ids = np.arange(1, 9)
    return expand_shells(
        ids[None, :], ids, FLAT_S8, np.array([thickness]), np.array([offset]), np.array([1])
    )


def test_expansion_levels_and_weights():
    """Bottom, middle, top at -(1/2 + o) t, -o t, (1/2 - o) t along n; printed combinations."""
    new_ids, coords, bricks, expansion = _flat_s8(offset=0.5)
    assert new_ids[0] == 9 and bricks.shape == (1, 20)
    np.testing.assert_allclose(coords[:3, 2], [-0.2, -0.1, 0.0])
    np.testing.assert_allclose(expansion.normals, np.tile([0.0, 0.0, 1.0], (8, 1)))
    assert expansion.corner.tolist() == [True] * 4 + [False] * 4
    ids = np.concatenate([np.arange(1, 9), new_ids])
    values = np.zeros((ids.size, 1))
    values[8:, 0] = np.tile([1.0, 4.0, 7.0], 8)  # bottom, middle, top of every node
    printed = expansion.printed(ids, values)
    np.testing.assert_allclose(printed[:4, 0], (1 + 16 + 7) / 6)  # corner: quadratic mean
    np.testing.assert_allclose(printed[4:8, 0], 4.0)  # midside: mean of bottom and top
    np.testing.assert_array_equal(printed[8:], values[8:])


def test_normal_of_a_tilted_plate():
    """The nodal normal of a plane element is the plane's, whichever way it is tilted."""
    ids = np.arange(1, 9)
    base = FLAT_S8
    angle = 0.3
    rotation = np.array(
        [[1, 0, 0], [0, np.cos(angle), -np.sin(angle)], [0, np.sin(angle), np.cos(angle)]]
    )
    _, coords, _, expansion = expand_shells(
        ids[None, :], ids, base @ rotation.T, np.array([0.2]), np.array([0.0]), np.array([1])
    )
    np.testing.assert_allclose(expansion.normals, np.tile(rotation[:, 2], (8, 1)), atol=1e-14)
    np.testing.assert_allclose(coords[2] - coords[0], 0.2 * rotation[:, 2], atol=1e-14)


def test_knot_is_refused():
    """Two elements folded by 90 degrees at a shared edge: ccx would make a knot."""
    ids = np.arange(1, 14)
    coords = np.array(
        [[0, 0, 0], [2, 0, 0], [2, 1, 0], [0, 1, 0], [1, 0, 0], [2, 0.5, 0], [1, 1, 0],
         [0, 0.5, 0], [2, 0, -2], [2, 1, -2], [2, 0, -1], [2, 0.5, -2], [2, 1, -1]],
        float,
    )  # fmt: skip
    conn = np.array([[1, 2, 3, 4, 5, 6, 7, 8], [2, 9, 10, 3, 11, 12, 13, 6]])
    with pytest.raises(ValueError, match="node 2: the normals of shell elements 2 and 1 differ"):
        expand_shells(conn, ids, coords, np.full(2, 0.1), np.zeros(2), np.array([1, 2]))
    with pytest.raises(ValueError, match="different thicknesses or offsets"):
        flat = coords.copy()
        flat[8:] = [[4, 0, 0], [4, 1, 0], [3, 0, 0], [4, 0.5, 0], [3, 1, 0]]
        expand_shells(conn, ids, flat, np.array([0.1, 0.2]), np.zeros(2), np.array([1, 2]))


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("FIX, 1, 3\n", "FIX, 4, 6\n"), "rotational dofs are supported only all fixed"),
        (("FIX, 1, 3\n", "FIX, 1, 3\n9, 1, 6, 0.1\n"), "rotational dofs are supported only"),
        (("*STEP\n", "*STEP\n*CLOAD\n9, 3, 1.0\n"), "CLOAD names the shell node 9"),
        (("FIX, 1, 3\n", "FIX, 1, 3\n12, 3, 3, 0.1\n"), "shell node 12 \\(an S8 midside"),
        (("0.2\n", "0.0\n"), "thickness must be > 0"),
        (
            ("*SHELL SECTION, ELSET=EALL, MATERIAL=M, OFFSET=0.3\n0.2\n", ""),
            "has no \\*SHELL SECTION",
        ),
    ],
    ids=["rotation-only", "rotation-prescribed", "cload", "midside-value", "thickness", "section"],
)
def test_refusals(tmp_path, change, message):
    text = plate_deck("hinged")
    old, new = change
    assert old in text
    path = write_deck(tmp_path, "bad", text.replace(old, new, 1))
    with pytest.raises(DeckError, match=message):
        read_deck(path)


def test_rotation_on_solid_node_and_spos_on_solid_are_refused(tmp_path):
    text = block_deck()
    path = write_deck(tmp_path, "a", text.replace("NTOP, 1, 2\n", "NTOP, 1, 6\n"))
    with pytest.raises(DeckError, match="dof 6 of node 5, which is not a shell node"):
        read_deck(path)
    path = write_deck(tmp_path, "b", text.replace("EFLOOR, SPOS", "EFLOOR, SPOS\nEBLOCK, SNEG"))
    with pytest.raises(DeckError, match="SPOS/SNEG on element 1, which is not a shell"):
        read_deck(path)


def test_deck_has_bricks_and_shell_record(tmp_path):
    deck = read_deck(write_deck(tmp_path, "p", plate_deck("supported")))
    assert list(deck.elements) == ["C3D20"]
    assert isinstance(deck.shells, ShellExpansion)
    np.testing.assert_array_equal(deck.shells.nodes, np.arange(1, 14))
    np.testing.assert_array_equal(deck.elements["C3D20"].ids, [1, 2])
    # node 8 (midside, held in 1-3): bottom + top = 0 per dof; corner 1: middle fixed
    bottom, _, top = deck.shells.expanded[7]
    tied = [e for e in deck.equations if e.nodes[0] == bottom]
    assert sorted(int(e.dofs[0]) for e in tied) == [1, 2, 3]
    assert all(e.nodes.tolist() == [bottom, top] for e in tied)
    middle = deck.shells.expanded[0, 1]
    assert any(middle in b.nodes and (b.first_dof, b.last_dof) == (1, 3) for b in deck.boundaries)
