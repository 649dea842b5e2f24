"""C3D20 / C3D20R decks (docs/method.md §13.5): mesh, constraints, faces, patch test, ccx's output.

The decks are C3D8 decks given midside nodes by ``tests/data/calculix/crossval/hex20.py``.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import cases
import numpy as np
import pytest
from helpers.decks import WARPED_CUBES
from hex20 import to_hex20

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.elements import ELEMENT_TYPES
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.calculix.model import build_model
from dolfinx_ntf.fem.constraints import num_equations

pytestmark = pytest.mark.serial

COMM = MPI.COMM_SELF
E, NU, P = 1000.0, 0.3, 10.0

# WARPED_CUBES loaded on top and printed.
_CUBE = (
    WARPED_CUBES
    + """*STEP
*STATIC
1., 1.
*DLOAD
2, P2, {P}
*NODE PRINT, NSET=NALL
U, RF
*EL PRINT, ELSET=EALL
S
*NODE FILE
U
*EL FILE
S
*END STEP
"""
)


def _cube(tmp_path: Path, element: str = "C3D20") -> Path:
    path = tmp_path / "cube20.inp"
    path.write_text(_CUBE.format(E=E, NU=NU, P=P))
    to_hex20(path, reduced=element == "C3D20R")
    return path


def test_c3d20_extrapolation_is_nearly_triquadratic():
    """ccx's fitted weights: the triquadratic field through the 27 values, changed by < 6e-6."""
    etype = ELEMENT_TYPES["C3D20"]
    points = etype.integration_points
    corners = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], float)
    corners = corners[[0, 1, 3, 2, 4, 5, 7, 6]]  # ccx order
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
             (2, 6), (3, 7)]  # fmt: skip
    nodes = np.vstack([corners, [(corners[a] + corners[b]) / 2 for a, b in edges]])

    def monomials(x):
        powers = [(a, b, c) for c in range(3) for b in range(3) for a in range(3)]
        return np.stack([x[:, 0] ** a * x[:, 1] ** b * x[:, 2] ** c for a, b, c in powers], axis=1)

    exact = monomials(nodes) @ np.linalg.inv(monomials(points))
    assert np.abs(etype.extrapolation - exact).max() < 6e-6
    np.testing.assert_allclose(etype.extrapolation.sum(axis=1)[:8], 0.99996, atol=2e-6)
    np.testing.assert_allclose(etype.extrapolation.sum(axis=1)[8:], 1.00005, atol=2e-6)


def test_c3d20_model_mesh_and_numbering(tmp_path):
    deck = read_deck(_cube(tmp_path))
    model = build_model(deck, COMM)
    V = model.V
    coords = V.tabulate_dof_coordinates()
    assert np.all(model.node_dof >= 0)
    np.testing.assert_array_equal(model.dof_node[model.node_dof], deck.node_ids)
    np.testing.assert_allclose(coords[model.node_dof], deck.node_coords, atol=1e-14)
    # 2 x 27 - 9 shared dofs: the 20-node elements' 32 nodes plus 11 face and 2 cell centres
    assert coords.shape[0] == deck.node_ids.size + 11 + 2
    centres = np.flatnonzero(model.dof_node < 0)
    assert centres.size == 13
    np.testing.assert_array_equal(np.sort(centres), np.unique(compat.cell_dofs(V)[:, 20:]))
    assert num_equations(model.constraints) == 3 * 13
    # the centres sit where the serendipity map of the 20 nodes puts them (the shared face too)
    x = np.asarray(deck.node_coords)
    block = deck.elements["C3D20"]
    for cell, element in zip(model.element_cell, deck.node_index(block.connectivity)):
        nodes = x[element]
        bottom = nodes[[0, 1, 2, 3]].sum(0) * -0.25 + nodes[[8, 9, 10, 11]].sum(0) * 0.5
        centre = nodes[:8].sum(0) * -0.25 + nodes[8:].sum(0) * 0.25
        cell_coords = coords[compat.cell_dofs(V)[cell]]
        assert np.min(np.linalg.norm(cell_coords - bottom, axis=1)) < 1e-14
        np.testing.assert_allclose(cell_coords[26], centre, atol=1e-14)


@pytest.mark.parametrize("element", ["C3D20", "C3D20R"])
def test_c3d20_uniaxial_patch_test(tmp_path, element):
    """Uniform pressure on a distorted two-element column: exact stresses, quad8 nodal loads."""
    path = _cube(tmp_path, element)
    result = run_job("cube20", path.parent, comm=COMM, progress=False)
    assert result.completed
    blocks = read_dat(tmp_path / "cube20.dat")
    (stress,) = [b for b in blocks if b.name == "S"]
    assert stress.values.shape == (2 * (27 if element == "C3D20" else 8), 6)
    expected = np.array([0.0, 0.0, -P, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(stress.values, np.tile(expected, (stress.values.shape[0], 1)),
                               atol=1e-9 * P)  # fmt: skip
    (u,) = [b for b in blocks if b.name == "U"]
    deck = read_deck(path)
    x = deck.node_coords[deck.node_index(u.labels)]
    np.testing.assert_allclose(u.values[:, 2], -P * x[:, 2] / E, atol=1e-12)
    np.testing.assert_allclose(u.values[:, 0], NU * P * x[:, 0] / E, atol=1e-12)
    # reactions of the bottom face: quad8's consistent loads, corners -1/12, midsides 1/3 of P A
    (rf,) = [b for b in blocks if b.name == "RF"]
    bottom = np.isclose(deck.node_coords[deck.node_index(rf.labels)][:, 2], 0.0)
    corner = np.isin(rf.labels, deck.elements[element].connectivity[:, :8])
    np.testing.assert_allclose(rf.values[bottom & corner, 2], -P / 12, atol=1e-10)
    np.testing.assert_allclose(rf.values[bottom & ~corner, 2], P / 3, atol=1e-10)
    assert rf.labels.size == deck.node_ids.size  # no face or cell centre in the output
    frd = read_frd(tmp_path / "cube20.frd")
    assert set(frd.element_types.tolist()) == {4}
    (s_frd,) = frd.blocks_named("STRESS")
    # ccx writes a uniform stress with its weights' row sums: 0.99996 at corners (and at C3D20R's
    # midside nodes, means of corners), 1.00005 at C3D20's midside nodes
    at_corner = np.isin(s_frd.nodes, deck.elements[element].connectivity[:, :8])
    np.testing.assert_allclose(s_frd.values[at_corner, 2], -P * 0.99996, rtol=2e-6)
    midside = 1.00005 if element == "C3D20" else 0.99996
    np.testing.assert_allclose(s_frd.values[~at_corner, 2], -P * midside, rtol=2e-6)


def test_c3d20_contact_faces_are_quad8(tmp_path):
    """Serendipity face centres are neither slave nor master nodes: quad8 faces, ccx's nodes."""
    case = next(c for c in cases.CASES if c.name == "hex20_linear_pressure")
    case.write(tmp_path)
    deck = read_deck(tmp_path / f"{case.name}.inp")
    model = build_model(deck, COMM)
    problem = model.create_problem(model.begin_step(0))
    (state,) = problem.states
    assert state.master_faces.face_type.name == "quad8"
    assert state.slave.faces.face_type.name == "quad8"
    assert np.all(model.dof_node[state.slave.nodes] >= 0)
    assert np.all(model.dof_node[state.master_faces.faces] >= 0)
    pair = deck.contact_pairs[0]
    surface = deck.surfaces[pair.slave]
    rows = np.searchsorted(deck.elements["C3D20"].ids, surface.elements)
    faces = ELEMENT_TYPES["C3D20"].faces[surface.faces - 1]
    slave_nodes = np.unique(deck.elements["C3D20"].connectivity[rows[:, None], faces])
    np.testing.assert_array_equal(np.sort(model.dof_node[state.slave.nodes]), slave_nodes)


def test_unsupported_hexahedra_are_refused_with_the_reason(tmp_path):
    path = tmp_path / "bad.inp"
    path.write_text(_CUBE.format(E=E, NU=NU, P=P).replace("TYPE=C3D8", "TYPE=C3D8R"))
    with pytest.raises(DeckError, match=r"element type C3D8R is not supported: .*hourglass"):
        read_deck(path)


@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
def test_c3d20_printed_and_file_results_match_ccx(tmp_path):
    """S at ccx's 27 points, RF and .frd blocks of a C3D20 contact deck against ccx 2.20."""
    from dolfinx_ntf.calculix.ccx import run_ccx

    case = next(c for c in cases.CASES if c.name == "hex20_linear_pressure")
    ours, theirs = tmp_path / "ours", tmp_path / "ccx"
    for directory in (ours, theirs):
        directory.mkdir()
        case.write(directory)
        deck = directory / f"{case.name}.inp"
        deck.write_text(
            deck.read_text().replace(
                "*END STEP",
                "*EL PRINT, ELSET=EALL\nS\n*NODE PRINT, NSET=NALL\nRF\n*NODE FILE\nU, RF\n"
                "*EL FILE\nS\n*END STEP",
            )
        )
    run_ccx(theirs, case.name, timeout=120)
    assert run_job(case.name, ours, comm=COMM, progress=False, tight=True).completed
    ccx_blocks = read_dat(theirs / f"{case.name}.dat")
    our_blocks = read_dat(ours / f"{case.name}.dat")
    assert [b.name for b in our_blocks] == [b.name for b in ccx_blocks]
    for a, b in zip(ccx_blocks, our_blocks):
        np.testing.assert_array_equal(a.labels, b.labels)
        if a.name in ("S", "RF"):
            scale = np.abs(a.values).max()
            assert np.abs(a.values - b.values).max() < 2e-6 * scale, a.name
    # the first Newton iteration's residual in % of the average element force (20 nodes each)
    ccx_cvg, our_cvg = (
        (d / f"{case.name}.cvg").read_text().splitlines()[4] for d in (theirs, ours)
    )
    assert float(our_cvg.split()[5]) == pytest.approx(float(ccx_cvg.split()[5]), rel=1e-3)
    ccx_frd, our_frd = read_frd(theirs / f"{case.name}.frd"), read_frd(ours / f"{case.name}.frd")
    for a, b in zip(ccx_frd.element_nodes, our_frd.element_nodes):
        np.testing.assert_array_equal(a, b)  # he20 node order as ccx writes it
    for name, bound in (("DISP", 1e-5), ("FORC", 1e-5), ("STRESS", 1e-5)):
        for a, b in zip(ccx_frd.blocks_named(name), our_frd.blocks_named(name)):
            np.testing.assert_array_equal(a.nodes, b.nodes)
            scale = np.abs(a.values).max()
            # STRESS: the triquadratic extrapolation of the 27 values differs by 2.7e-5
            assert np.abs(a.values - b.values).max() < bound * scale, name


def test_c3d20_node_surface_midside_nodes_take_no_face_area(tmp_path):
    """ccx's rule: midside nodes of a TYPE=NODE slave surface get the fallback area, not 24/100."""
    case = next(c for c in cases.CASES if c.name == "hex20_nodal")
    case.write(tmp_path)
    deck = read_deck(tmp_path / f"{case.name}.inp")
    model = build_model(deck, COMM)
    problem = model.create_problem(model.begin_step(0))
    (state,) = problem.states
    listed = deck.surfaces[deck.contact_pairs[0].slave].nodes
    np.testing.assert_array_equal(np.sort(model.dof_node[state.slave.nodes]), np.sort(listed))
    corners = np.isin(model.dof_node[state.slave.nodes], deck.elements["C3D20"].connectivity[:, :8])
    np.testing.assert_array_equal(state.slave.faceless, ~corners)
    assert np.sum(~corners) == 12  # the midside nodes of the punch's bottom
    from dolfinx_ntf.contact.pairing import slave_areas

    areas = slave_areas(state.slave, problem.current_coordinates())
    assert np.all(areas[~corners] == 0.0) and np.all(areas[corners] > 0.0)


def test_node_surface_checks_midside_nodes():
    from dolfinx_ntf.fem.surfaces import NodeSurface

    with pytest.raises(ValueError, match="midside_nodes must be non-negative"):
        NodeSurface(np.array([0, 1]), "s", midside_nodes=np.array([-1]))
