"""``*TRANSFORM`` (local directions of nodes) for ``*BOUNDARY`` against CalculiX 2.20.

A block of 2 x 2 C3D8 whose left face has a cylindrical system about the z axis: its nodes are
held in the circumferential direction (zero: equations), one also radially (along x there: a
global dof) and one lifted along the axis (a nonzero value along a global axis), under forces on
the right face. The nodes without a transform print U and RF as ccx's to its digits; the
transformed nodes' displacements, turned into their local directions, equal the rows ccx prints
for them with its ``L`` mark; the refusals are tested without ccx (docs/method.md §28).
"""

from __future__ import annotations

import logging
import re
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import quiet_logs
from helpers.decks import UNIT_CUBE_CORNERS

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.deck.transforms import ON_AXIS, Transform, axis_normal, local_directions
from dolfinx_ntf.calculix.job import run_job

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")


def _block(print_set: str = "REST", *, model_bc: str = "LEFT, 2, 2", step_bc: str = "") -> str:
    """The deck (3 x 3 x 2 nodes, x in [1, 2], y in [-0.2, 0.8], z in [0, 0.5])."""
    nodes, ids = [], {}
    for iz in range(2):
        for iy in range(3):
            for ix in range(3):
                ids[ix, iy, iz] = len(nodes) + 1
                nodes.append((len(nodes) + 1, 1 + 0.5 * ix, 0.5 * iy - 0.2, 0.5 * iz))
    cells = []
    for iy in range(2):
        for ix in range(2):
            corners = [(ix, iy), (ix + 1, iy), (ix + 1, iy + 1), (ix, iy + 1)]
            cells.append([ids[i, j, 0] for i, j in corners] + [ids[i, j, 1] for i, j in corners])
    left = [ids[0, iy, iz] for iy in range(3) for iz in range(2)]
    rest = [n for n, *_ in nodes if n not in left]
    right = [ids[2, iy, iz] for iy in range(3) for iz in range(2)]
    bottom = [ids[ix, iy, 0] for ix in range(3) for iy in range(3)]

    def join(values) -> str:
        return ", ".join(str(v) for v in values)

    return (
        "*NODE, NSET=NALL\n"
        + "\n".join(f"{n}, {x!r}, {y!r}, {z!r}" for n, x, y, z in nodes)
        + "\n*ELEMENT, TYPE=C3D8, ELSET=EALL\n"
        + "\n".join(f"{k + 1}, {join(c)}" for k, c in enumerate(cells))
        + f"\n*NSET, NSET=LEFT\n{join(left)}\n*NSET, NSET=REST\n{join(rest)}"
        + f"\n*NSET, NSET=RIGHT\n{join(right)}\n*NSET, NSET=BOTTOM\n{join(bottom)}"
        + f"\n*NSET, NSET=PIN\n{ids[0, 0, 0]}\n*NSET, NSET=LIFT\n{ids[0, 2, 1]}\n"
        + "*TRANSFORM, NSET=LEFT, TYPE=C\n0., 0., 0., 0., 0., 1.\n"
        + "*MATERIAL, NAME=STEEL\n*ELASTIC\n1000., 0.3\n"
        + "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"
        + f"*BOUNDARY\n{model_bc}\nBOTTOM, 3, 3\nPIN, 1, 1\n"
        + f"*STEP\n*STATIC\n*BOUNDARY\nLIFT, 3, 3, 0.001\n{step_bc}"
        + "*CLOAD\nRIGHT, 1, 1.0\nRIGHT, 2, 0.5\n"
        + f"*NODE PRINT, NSET={print_set}\nU, RF\n*END STEP\n"
    ).replace("\n\n", "\n")


def _local_rows(path: Path) -> dict[int, np.ndarray]:
    """The ``L``-marked displacement rows of a ccx ``.dat`` (its local directions)."""
    rows, inside = {}, False
    for line in path.read_text().splitlines():
        if "displacements" in line:
            inside = True
        elif "forces" in line:
            inside = False
        match = re.fullmatch(r"\s*(\d+)((?:\s+\S+){3})\s+L\s*", line)
        if inside and match:
            rows[int(match.group(1))] = np.array([float(t) for t in match.group(2).split()])
    return rows


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_cylindrical_transform_agrees_with_ccx(tmp_path: Path) -> None:
    comm = MPI.COMM_WORLD
    root = Path(comm.bcast(str(tmp_path), root=0))
    ccx_dir, ntf_dir = root / "ccx", root / "ntf"
    if comm.rank == 0:
        for d in (ccx_dir, ntf_dir):
            d.mkdir()
            (d / "block.inp").write_text(_block())
        (ccx_dir / "all.inp").write_text(_block("NALL"))
        run_ccx(ccx_dir, "block", timeout=120)
        run_ccx(ccx_dir, "all", timeout=120)
    comm.barrier()
    with quiet_logs(logging.ERROR):
        result = run_job("block", ntf_dir, comm=comm, progress=False)
    assert result.completed
    if comm.rank != 0:
        return
    ours, theirs = read_dat(ntf_dir / "block.dat"), read_dat(ccx_dir / "block.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    for a, b in zip(ours, theirs):
        np.testing.assert_array_equal(a.labels, b.labels)
        assert np.abs(a.values - b.values).max() <= 1e-6 * np.abs(b.values).max(), a.name
    deck = result.model.deck
    local = _local_rows(ccx_dir / "all.dat")
    assert sorted(local) == deck.transformed_nodes.tolist()
    transform = Transform("LEFT", "C", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), None)
    rows = deck.node_index(deck.transformed_nodes)
    axes = local_directions(transform, deck.node_coords[rows])
    u = result.last.displacement_of(deck.transformed_nodes)
    ours_local = np.einsum("nij,nj->ni", axes, u)
    expected = np.array([local[n] for n in deck.transformed_nodes.tolist()])
    scale = np.abs(expected).max()
    np.testing.assert_allclose(ours_local, expected, rtol=0, atol=1e-6 * scale)
    assert np.abs(expected[:, 1]).max() == 0.0  # held circumferentially
    assert np.abs(expected[:, 0]).max() > 0.1 * scale  # free radially: equations, not x = 0


def _deck(tmp_path: Path, text: str):
    path = tmp_path / "deck.inp"
    path.write_text(text)
    return read_deck(path)


def test_boundaries_in_global_dofs(tmp_path: Path) -> None:
    """Axial (z) lines become global dof 3 with the value; circumferential zeros become one
    equation per node whose dependent term is its largest; a node held radially and
    circumferentially gets x = y = 0."""
    deck = _deck(tmp_path, _block(model_bc="LEFT, 2, 2\nPIN, 1, 2"))
    lift = [b for b in deck.steps[0].boundaries if b.target == "LIFT"]
    assert [(b.first_dof, b.last_dof, b.value) for b in lift] == [(3, 3, 0.001)]
    pin = int(deck.nsets["PIN"][0])
    held = {(int(b.nodes[0]), b.first_dof) for b in deck.boundaries if b.nodes.size == 1}
    assert {(pin, 1), (pin, 2)} <= held
    equations = {int(e.nodes[0]): e for e in deck.equations}
    assert pin not in equations and len(equations) == 5
    for node, equation in equations.items():
        x, y, _ = deck.node_coords[deck.node_index(np.array([node]))[0]]
        assert equation.dofs.tolist() == ([1, 2] if abs(y) > x else [2, 1])
        direction = np.zeros(3)
        direction[equation.dofs - 1] = equation.coefficients
        np.testing.assert_allclose(np.cross(direction, [-y, x, 0.0]), 0.0, atol=1e-14)


def test_rectangular_transform_direction(tmp_path: Path) -> None:
    """TYPE=R with local x along -y: local dof 1 is global dof 2 with the value's sign turned."""
    text = _block(model_bc="").replace(
        "*TRANSFORM, NSET=LEFT, TYPE=C\n0., 0., 0., 0., 0., 1.",
        "*TRANSFORM, NSET=LEFT\n0., -1., 0., 1., 0., 0.",
    )
    text = text.replace("LIFT, 3, 3, 0.001", "LIFT, 1, 1, 0.001")
    deck = _deck(tmp_path, text)
    lift = [b for b in deck.steps[0].boundaries if b.target == "LIFT"]
    assert [(b.first_dof, b.value) for b in lift] == [(2, -0.001)]


@pytest.mark.parametrize(
    ("model_bc", "step_bc", "what"),
    [
        ("LEFT, 2, 2, 0.01", "", "only zero values"),
        ("LEFT, 3, 3", "LEFT, 1, 1\n", "only zero values in the model definition"),
    ],
)
def test_unsupported_boundaries_are_refused(tmp_path, model_bc, step_bc, what) -> None:
    with pytest.raises(DeckError, match=what) as info:
        _deck(tmp_path, _block(model_bc=model_bc, step_bc=step_bc))
    assert "deck.inp:" in str(info.value) and "local direction" in str(info.value)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_nodes_on_the_axis_keep_the_global_directions(tmp_path: Path) -> None:
    """The axis through two nodes of the left face: ccx 2.20 holds them along global y (their
    local 2 is global y); every printed block equals ccx's."""
    text = _block().replace("0., 0., 0., 0., 0., 1.", "1., -0.2, 0., 1., -0.2, 1.")
    deck = _deck(tmp_path, text)
    on_axis = {1, 10}
    held = {(int(b.nodes[0]), b.first_dof) for b in deck.boundaries if b.nodes.size == 1}
    assert {(n, 2) for n in on_axis} <= held
    assert on_axis.isdisjoint(int(e.nodes[0]) for e in deck.equations)
    ccx_dir, ntf_dir = tmp_path / "ccx", tmp_path / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir()
        (d / "block.inp").write_text(text)
    run_ccx(ccx_dir, "block", timeout=120)
    result = run_job("block", ntf_dir, comm=MPI.COMM_SELF, progress=False)
    assert result.completed
    ours, theirs = read_dat(ntf_dir / "block.dat"), read_dat(ccx_dir / "block.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    for a, b in zip(ours, theirs):
        np.testing.assert_array_equal(a.labels, b.labels)
        assert np.abs(a.values - b.values).max() <= 1e-6 * np.abs(b.values).max(), a.name


def test_cload_on_transformed_nodes_is_refused(tmp_path: Path) -> None:
    text = _block().replace("*CLOAD\nRIGHT, 1, 1.0", "*CLOAD\nLIFT, 1, 1.0\nRIGHT, 1, 1.0")
    with pytest.raises(DeckError, match=r"CLOAD on node \d+, which has a \*TRANSFORM") as info:
        _deck(tmp_path, text)
    assert "deck.inp:" in str(info.value)


def test_equation_on_transformed_nodes_is_refused(tmp_path: Path) -> None:
    text = _block().replace(
        "*BOUNDARY\nLEFT, 2, 2", "*EQUATION\n2\nLIFT, 1, 1.0, 2, 1, -1.0\n*BOUNDARY\nLEFT, 2, 2"
    )
    with pytest.raises(DeckError, match=r"EQUATION on node \d+, which has a \*TRANSFORM"):
        _deck(tmp_path, text)


def test_node_print_of_transformed_nodes_is_refused(tmp_path: Path) -> None:
    (tmp_path / "deck.inp").write_text(_block("NALL"))
    with pytest.raises(NotImplementedError, match="local directions"):
        run_job("deck", tmp_path, comm=MPI.COMM_SELF, progress=False)


def _one_node_deck(node: tuple[float, float, float], axis: tuple[float, float, float]) -> str:
    """One C3D8 whose node 1 has a cylindrical system about ``axis`` through the origin.

    Three steps move node 1 by 1e-3 along its local 1, 2 and 3 in turn (the others held), so
    the printed global displacements are 1e-3 times the local directions.
    """
    coords = np.asarray(node) + np.asarray(UNIT_CUBE_CORNERS, dtype=float)
    coords[0] = node
    text = "*NODE, NSET=NALL\n" + "".join(
        f"{k}, {x!r}, {y!r}, {z!r}\n" for k, (x, y, z) in enumerate(coords.tolist(), start=1)
    )
    text += "*ELEMENT, TYPE=C3D8, ELSET=EALL\n1, 1, 2, 3, 4, 5, 6, 7, 8\n"
    text += "*NSET, NSET=ONE\n1\n*NSET, NSET=REST\n2, 3, 4, 5, 6, 7, 8\n"
    text += "*TRANSFORM, NSET=ONE, TYPE=C\n0., 0., 0., " + ", ".join(map(repr, axis)) + "\n"
    text += "*MATERIAL, NAME=M\n*ELASTIC\n1000., 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=M\n"
    text += "*BOUNDARY\nREST, 1, 3\n"
    for i in (1, 2, 3):
        text += "*STEP\n*STATIC\n*BOUNDARY, OP=NEW\nREST, 1, 3\n"
        text += "".join(f"ONE, {j}, {j}, {0.001 if j == i else 0.0}\n" for j in (1, 2, 3))
        text += "*NODE PRINT, NSET=ONE, GLOBAL=YES\nU\n*END STEP\n"
    return text


#: Node 1 and the axis: along x and -x, tilted (three kinds: ccx's rule takes the first global
#: direction the axis has a component in), a node 9.2e-16 off a y axis (metalforming's punch
#: apex; ccx: on the axis) and one 1e-9 off it (ccx: off the axis, radial along x).
AXES = {
    "x": ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)),
    "minus_x": ((0.0, 0.0, 0.0), (-1.0, 0.0, 0.0)),
    "tilted_123": ((0.0, 0.0, 0.0), (1.0, 2.0, 3.0)),
    "tilted_m1m23": ((0.0, 0.0, 0.0), (-1.0, -2.0, 3.0)),
    "tilted_032": ((0.0, 0.0, 0.0), (0.0, 3.0, 2.0)),
    "y_near_9e-16": ((-9.18485e-16, 0.25, 0.0), (0.0, 1.0, 0.0)),
    "y_off_1e-9": ((1e-9, 0.0, 0.0), (0.0, 1.0, 0.0)),
}


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", list(AXES))
def test_local_directions_on_the_axis_are_ccx_ones(tmp_path: Path, case: str) -> None:
    """ccx 2.20's local directions at a node on (or next to) a cylindrical axis, read from its
    global U after a unit move along each local direction, equal :func:`local_directions`
    (docs/method.md §33.6) to ccx's printed digits."""
    node, axis = AXES[case]
    run_ccx_dir = tmp_path / "ccx"
    run_ccx_dir.mkdir()
    (run_ccx_dir / "t.inp").write_text(_one_node_deck(node, axis))
    run_ccx(run_ccx_dir, "t", timeout=120)
    blocks = read_dat(run_ccx_dir / "t.dat")
    assert [b.name for b in blocks] == ["U"] * 3
    theirs = np.array([b.values[0] / 0.001 for b in blocks])
    np.testing.assert_allclose(theirs @ theirs.T, np.eye(3), atol=1e-6)  # ccx's are orthonormal
    ours = local_directions(Transform("ONE", "C", (0.0, 0.0, 0.0), axis, None), np.array([node]))
    np.testing.assert_allclose(ours[0], theirs, rtol=0, atol=1e-6)


def test_axis_normal_is_ccx_rule() -> None:
    """Local 1 on an axis lies in the plane of the first global direction the axis has a
    component in and the next one, normal to the axis (without ccx: its measured values)."""
    for axis in (
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 2.0, 3.0],
        [0.0, 3.0, 2.0],
    ):
        axis = np.asarray(axis) / np.linalg.norm(axis)
        normal = axis_normal(axis)
        assert abs(normal @ axis) < 1e-15 and abs(np.linalg.norm(normal) - 1.0) < 1e-15
    np.testing.assert_allclose(
        axis_normal(np.array([1.0, 2.0, 3.0]) / 14**0.5), [-2 / 5**0.5, 1 / 5**0.5, 0.0]
    )
    np.testing.assert_allclose(axis_normal(np.array([0.0, 1.0, 0.0])), [0.0, 0.0, 1.0])
    np.testing.assert_allclose(axis_normal(np.array([1e-11, 1.0, 0.0])), [0.0, 0.0, 1.0])
    near = local_directions(
        Transform("N", "C", (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), None),
        np.array([[0.5 * ON_AXIS, 0.3, 0.0], [2.0 * ON_AXIS, 0.3, 0.0]]),
    )
    np.testing.assert_allclose(near[:, 0], [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
