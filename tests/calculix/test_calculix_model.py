"""CalculiX decks as dolfinx models and ccx-like runs: mesh conversion, load rules, analytical
answers, the two-cube deck against ccx 2.20's stored output, the command line and bad decks.

Decks live in ``tests/data/calculix/model/`` (``make_decks.py`` generates them).
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
import scipy.optimize

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.__main__ import main
from dolfinx_ntf.calculix import job as job_module
from dolfinx_ntf.calculix.cel import read_cel
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.job import JobError, run_job
from dolfinx_ntf.calculix.model import CELL_PERMUTATIONS, INTEGRATION_POINTS, build_model
from dolfinx_ntf.fem.surfaces import FacetSurface, NodeSurface

pytestmark = pytest.mark.serial

DATA = Path(__file__).parents[1] / "data" / "calculix"
MODEL = DATA / "model"
COMM = MPI.COMM_WORLD

# Uniaxial cube decks: E, nu, top pressure (make_decks.cube).
E, NU, P = 1000.0, 0.3, 10.0
TET_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]  # ccx C3D10 midside nodes 5..10


def _copy(tmp_path: Path, name: str, source: Path = MODEL) -> Path:
    shutil.copy(source / f"{name}.inp", tmp_path / f"{name}.inp")
    return tmp_path


def _run(tmp_path: Path, name: str, **options):
    return run_job(name, _copy(tmp_path, name), comm=COMM, progress=False, **options)


def _blocks(path: Path, name: str, time: float | None = None):
    return [b for b in read_dat(path) if b.name == name and (time is None or b.time == time)]


# ----------------------------------------------------------------------------- mesh conversion


@pytest.fixture(scope="module", params=["c3d8", "c3d4", "c3d10", "c3d10_curved"])
def cube(request):
    deck = read_deck(MODEL / f"cube_{request.param}.inp")
    return deck, build_model(deck, COMM)


def _cell_input_nodes(model):
    """Deck node rows of each cell's geometry nodes, in dolfinx order."""
    mesh = model.mesh
    num_cells = mesh.topology.index_map(3).size_local
    dofmap = compat.geometry_dofs(mesh)[:num_cells]
    return np.asarray(mesh.geometry.input_global_indices)[dofmap]


def test_mesh_volume_and_positive_jacobians(cube):
    _, model = cube
    mesh = model.mesh
    volume = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * ufl.dx(domain=mesh)))
    assert volume == pytest.approx(1.0, rel=1e-12)
    # every element keeps a positive Jacobian at its corners and at ccx's integration points
    etype = model.element_type.name
    corners = {"C3D8": [[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)]}.get(
        etype, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    )
    points = np.vstack([np.array(corners, float), INTEGRATION_POINTS[etype]])
    expression = dolfinx.fem.Expression(ufl.JacobianDeterminant(mesh), points)
    cells = np.arange(mesh.topology.index_map(3).size_local, dtype=np.int32)
    det = compat.evaluate_expression(expression, mesh, cells)
    assert det.shape == (cells.size, points.shape[0])
    assert np.all(det > 0)


def test_node_and_element_maps(cube):
    deck, model = cube
    coords = model.V.tabulate_dof_coordinates()
    assert np.all(model.node_dof >= 0)
    np.testing.assert_array_equal(model.dof_node[model.node_dof], deck.node_ids)
    np.testing.assert_allclose(coords[model.node_dof], deck.node_coords, atol=1e-14)
    assert np.unique(model.node_dof).size == deck.node_ids.size == coords.shape[0]
    # each element's cell holds the element's nodes in dolfinx order
    block = deck.elements[model.element_type.name]
    rows = deck.node_index(block.connectivity)[:, CELL_PERMUTATIONS[model.element_type.name]]
    np.testing.assert_array_equal(_cell_input_nodes(model)[model.element_cell], rows)
    np.testing.assert_array_equal(model.cell_element[model.element_cell], block.ids)
    np.testing.assert_array_equal(model.element_cells(block.ids[::-1]), model.element_cell[::-1])
    # vertices map to the corner nodes; midside nodes have none
    corner_nodes = np.unique(block.connectivity[:, : block.type.num_corners])
    vertex = model.node_vertex[deck.node_index(corner_nodes)]
    assert np.all(vertex >= 0) and np.unique(vertex).size == corner_nodes.size
    assert np.sum(model.node_vertex >= 0) == corner_nodes.size


def _midside_mismatch(model, deck, cells_nodes):
    """Largest distance between ccx midside nodes and dolfinx's geometry at the edge midpoints."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    midpoints = np.array([(corners[a] + corners[b]) / 2 for a, b in TET_EDGES])
    block = deck.elements["C3D10"]
    worst = 0.0
    geometry_of_mesh = model.mesh.geometry
    # dolfinx 0.11 keeps one coordinate map per cell type (cmap is deprecated there)
    cmap = geometry_of_mesh.cmaps[0] if compat.DOLFINX_VERSION >= (0, 11) else geometry_of_mesh.cmap
    for cell, element in zip(model.element_cell, block.connectivity):  # 48 cells: a small loop
        geometry = geometry_of_mesh.x[cells_nodes[cell]]
        mapped = cmap.push_forward(midpoints, geometry)
        expected = deck.node_coords[deck.node_index(element[4:])]
        worst = max(worst, float(np.abs(mapped - expected).max()))
    return worst


def test_c3d10_midside_permutation_is_geometric():
    """Reference edge midpoints map onto ccx's midside nodes (moved off the edges in the deck)."""
    deck = read_deck(MODEL / "cube_c3d10_curved.inp")
    model = build_model(deck, COMM)
    num_cells = model.mesh.topology.index_map(3).size_local
    dofmap = compat.geometry_dofs(model.mesh)[:num_cells]
    assert _midside_mismatch(model, deck, dofmap) < 1e-14
    # the check can fail: ccx's own order read as dolfinx's puts nodes on the wrong edges
    inverse = np.argsort(CELL_PERMUTATIONS["C3D10"])
    assert _midside_mismatch(model, deck, dofmap[:, inverse]) > 0.1


def test_surfaces_become_facet_tags_and_vertex_sets():
    deck = read_deck(DATA / "two_cubes.inp")
    model = build_model(deck, COMM)
    master = model.surfaces["MASTER"]
    assert isinstance(master, FacetSurface)
    facets = master.tags.indices[master.tags.values == 1]
    assert facets.size == 1
    facet_vertices = model.mesh.topology.connectivity(2, 0).links(facets[0])
    x = model.mesh.geometry.x
    vertex_geometry = compat.entities_to_geometry(model.mesh, 0, facet_vertices)
    np.testing.assert_allclose(np.sort(x[vertex_geometry.ravel(), 2]), [1.0] * 4)
    np.testing.assert_array_equal(model.face_nodes_of("MASTER", facets), [[5, 6, 7, 8]])
    np.testing.assert_array_equal(model.face_nodes_of("SLAVE", model.surface_faces["SLAVE"][0]),
                                  [[14, 13, 12, 11]])  # fmt: skip
    assert model.pairs[0].name == "SLAVE-MASTER"

    deck = read_deck(MODEL / "blocks.inp")
    model = build_model(deck, COMM)
    slave = model.surfaces["SLAVE"]
    assert isinstance(slave, NodeSurface)
    nodes = deck.nsets["SLAVENODES"]
    vertex_coords = model.V.tabulate_dof_coordinates()[model.node_dofs(nodes)]
    np.testing.assert_array_equal(
        np.sort(slave.vertices), np.sort(model.node_vertex[deck.node_index(nodes)])
    )
    np.testing.assert_allclose(vertex_coords[:, 2], 0.5)


@pytest.mark.parametrize(
    "behavior, expected",
    [
        ("EXPONENTIAL\n1.0e-3, 0.5", "ExponentialLaw(c0=0.001, p0=0.5)"),
        ("LINEAR\n1.0e7, 1.0, 1.0e-3", "LinearLaw(slope=10000000.0, tension=1.0, c0=0.001)"),
        ("LINEAR\n, 2.0", "LinearLaw(slope=10500000.0, tension=2.0, c0=0.001)"),
        ("HARD", "LinearLaw(slope=10500000.0, tension=3.0, c0=0.001)"),
        (
            "TABULAR\n0.0, 0.0\n10.0, 1.0e-3",
            "TabularLaw(pressures=[0.0, 10.0], overclosures=[0.0, 0.001])",
        ),
    ],
)
def test_contact_laws_from_surface_behavior(tmp_path, behavior, expected):
    """ccx defaults from the first *ELASTIC (E = 210000): K = 50 E, sigma_inf = E / 70000."""
    text = (DATA / "two_cubes.inp").read_text()
    text = text.replace("LINEAR\n1.0e7, 1.0, 1.0e-3", behavior)
    (tmp_path / "law.inp").write_text(text)
    model = build_model(read_deck(tmp_path / "law.inp"), COMM)
    assert repr(model.pairs[0].interaction.law) == expected
    assert model.pairs[0].small_sliding is False and model.pairs[0].interaction.friction is None


# ----------------------------------------------------------------------------- load rules


def test_load_schedule_follows_ccx_rules():
    """Forces, pressures and prescribed displacements over three steps (see model.py's rules)."""
    deck = read_deck(MODEL / "loads_pressure.inp")
    model = build_model(deck, COMM)

    def force(node: int, dof: int) -> float:
        return model.nodal_loads.x.array[3 * model.node_dofs([node])[0] + dof]

    groups = {}
    for tag_value in np.unique(model.pressure_tags.values):
        facet = model.pressure_tags.indices[model.pressure_tags.values == tag_value][0]
        z = dolfinx.mesh.compute_midpoints(model.mesh, 2, np.array([facet], np.int32))[0]
        groups["P2" if np.isclose(z[2], 1.0) else "P4"] = model.pressures[tag_value - 1]
    assert set(groups) == {"P2", "P4"}

    model.begin_step(0)
    model.set_time(0, 0.5)
    assert force(7, 2) == pytest.approx(-5.0)  # ramp to -10
    assert force(8, 2) == pytest.approx(-5.0)  # -5 twice in one step add up to -10, ramped
    assert force(5, 0) == pytest.approx(4.0)  # amplitude STEPAMP(0.5) = 1
    assert groups["P2"].value == pytest.approx(15.0)  # 20 + 10 in one step, ramped
    model.set_time(0, 1.0)
    assert force(5, 0) == pytest.approx(2.0)  # STEPAMP(1) = 0.5

    model.u.x.array[:] = 0.02  # the current displacement where step 2 starts
    bcs = model.begin_step(1)
    assert sum(bc.dof_indices()[0].size for bc in bcs) == 13  # 4 nodes x 3, plus node 6 x
    model.set_time(1, 1.0)  # half of the period 2
    assert force(7, 2) == pytest.approx(-15.0)  # -10 -> -20 (replaced in a new step)
    assert force(8, 2) == pytest.approx(-10.0)  # kept
    assert force(5, 0) == pytest.approx(2.0)  # amplitude dropped, value at the end of step 1 kept
    assert groups["P2"].value == pytest.approx(15.0)  # OP=NEW: 30 ramps down to 0
    assert groups["P4"].value == pytest.approx(25.0)
    g = [compat.boundary_values(bc).x.array for bc in bcs]
    assert np.any(
        np.isclose(np.concatenate(g), 0.5 * (0.02 + 0.01))
    )  # node 6 x: ramp from u to 0.01

    bcs = model.begin_step(2)
    assert sum(bc.dof_indices()[0].size for bc in bcs) == 12  # OP=NEW released node 6
    model.set_time(2, 0.5)  # total time 3.5
    assert force(7, 2) == pytest.approx(-10.0)  # OP=NEW: removed loads ramp down to 0 (as ccx)
    assert force(8, 2) == pytest.approx(-5.0)
    assert force(6, 1) == pytest.approx(8.0 * 3.5 / 4.0)  # TOTALAMP at total time 3.5
    assert groups["P4"].value == pytest.approx(50.0) and groups["P2"].value == 0.0


def test_load_rules_match_ccx(tmp_path):
    """NLGEOM brick, three steps: displacements equal ccx 2.20's (loads_ccx.dat) per increment."""
    result = _run(tmp_path, "loads")
    ours = _blocks(tmp_path / "loads.dat", "U")
    reference = _blocks(MODEL / "loads_ccx.dat", "U")
    assert (
        [b.time for b in ours] == [b.time for b in reference] == [o.time for o in result.increments]
    )
    for a, b in zip(ours, reference):
        np.testing.assert_array_equal(a.labels, b.labels)
        np.testing.assert_allclose(a.values, b.values, atol=2e-8, rtol=0)
    assert [(o.step, o.increment) for o in result.increments][:5] == [
        (1, 1),
        (1, 2),
        (1, 3),
        (1, 4),
        (2, 1),
    ]


# ----------------------------------------------------------------------------- analytical answers


@pytest.mark.parametrize("etype", ["C3D8", "C3D4", "C3D10"])
def test_uniaxial_compression(tmp_path, etype):
    """Cube on rollers under a top pressure: u = p/E (nu x, nu y, -z), sigma_zz = -p everywhere."""
    name = f"cube_{etype.lower()}"
    result = _run(tmp_path, name)
    out = result.last
    deck = read_deck(tmp_path / f"{name}.inp")
    x = deck.node_coords[deck.node_index(out.node_ids)]
    expected = P / E * np.column_stack([NU * x[:, 0], NU * x[:, 1], -x[:, 2]])
    np.testing.assert_allclose(out.displacement, expected, atol=1e-12)
    total = _blocks(tmp_path / f"{name}.dat", "RF_TOTAL")[0]
    np.testing.assert_allclose(total.values[0], [0.0, 0.0, P], atol=1e-10)
    stress = _blocks(tmp_path / f"{name}.dat", "S")[0]
    q = INTEGRATION_POINTS[etype].shape[0]
    assert stress.values.shape == (deck.num_elements * q, 6)
    uniaxial = np.tile([0, 0, -P, 0, 0, 0], (stress.values.shape[0], 1))
    np.testing.assert_allclose(stress.values, uniaxial, atol=1e-9)
    assert out.time == 1.0 and result.completed and not out.contact


def test_nlgeom_uniaxial_follower_pressure(tmp_path):
    """St.Venant-Kirchhoff cube, follower pressure p on the deformed top: Cauchy sigma_zz = -p."""
    result = _run(tmp_path, "cube_nlgeom", tight=True)
    mu, lmbda = E / 2 / (1 + NU), E * NU / ((1 + NU) * (1 - 2 * NU))
    for out, pressure in zip(result.increments, (50.0, 100.0)):

        def equations(stretch, pressure=pressure):
            l1, l3 = stretch
            e1, e3 = (l1**2 - 1) / 2, (l3**2 - 1) / 2
            s11 = 2 * mu * e1 + lmbda * (2 * e1 + e3)
            s33 = 2 * mu * e3 + lmbda * (2 * e1 + e3)
            return [s11, l3 * s33 / l1**2 + pressure]  # lateral Cauchy 0, axial -p

        l1, l3 = scipy.optimize.fsolve(equations, [1.0, 1.0], xtol=1e-13)
        corner = out.displacement_of(
            [int(read_deck(tmp_path / "cube_nlgeom.inp").nsets["CORNER"][0])]
        )[0]
        np.testing.assert_allclose(corner, [l1 - 1, l1 - 1, l3 - 1], rtol=1e-8)
        stress = _blocks(tmp_path / "cube_nlgeom.dat", "S", out.time)[0].values
        np.testing.assert_allclose(stress[:, 2], -pressure, rtol=1e-8)
        np.testing.assert_allclose(stress[:, [0, 1, 3, 4, 5]], 0.0, atol=1e-8 * pressure)
    assert l3 - 1 < -0.1  # large strain: the small-strain answer would be off by percents


def test_c3d10_stress_points_in_ccx_order(tmp_path):
    """u = (a x^2, b y^2, c z^2), nu = 0: sxx = 2 E a x at each point.

    ccx 2.20 orders the four points (a,a,a), (b,a,a), (a,b,a), (a,a,b) (measured with this deck),
    which INTEGRATION_POINTS reproduces.
    """
    _run(tmp_path, "c3d10_points")
    stress = _blocks(tmp_path / "c3d10_points.dat", "S")[0]
    np.testing.assert_array_equal(stress.labels, [[1, 1], [1, 2], [1, 3], [1, 4]])
    points = INTEGRATION_POINTS["C3D10"]
    expected = 2 * E * np.array([1e-3, 2e-3, 3e-3]) * points
    np.testing.assert_allclose(stress.values[:, :3], expected, rtol=1e-6)  # 7 digits in .dat
    a, b = 0.1381966, 0.5854102
    np.testing.assert_allclose(points, [[a, a, a], [b, a, a], [a, b, a], [a, a, b]], atol=1e-7)


# ----------------------------------------------------------------------------- contact through the


def test_two_cubes_cli_matches_ccx_output(tmp_path, capsys):
    """The two-cube deck through ``main``: .cel identical to ccx 2.20's, .dat blocks equal to its
    numbers (ccx converged these increments to a residual of ~1e-10, so the answers agree)."""
    _copy(tmp_path, "two_cubes", DATA)
    assert main(["run", str(tmp_path / "two_cubes")]) == 0
    assert "Wrote" in capsys.readouterr().out
    assert (tmp_path / "two_cubes.cel").read_text() == (DATA / "two_cubes.cel").read_text()
    ours, reference = read_dat(tmp_path / "two_cubes.dat"), read_dat(DATA / "two_cubes.dat")
    assert [(b.name, b.time, b.set) for b in ours] == [(b.name, b.time, b.set) for b in reference]
    for a, b in zip(ours, reference):
        np.testing.assert_array_equal(a.labels, b.labels)
        scale = np.abs(b.values).max()
        np.testing.assert_allclose(
            a.values, b.values, atol=2e-6 * scale, err_msg=f"{b.name} {b.time}"
        )
    assert (tmp_path / "two_cubes.xdmf").is_file() and (tmp_path / "two_cubes.h5").is_file()
    # without CONTACT ELEMENTS a stale .cel goes, as ccx deletes it at start
    deck = (tmp_path / "two_cubes.inp").read_text().replace("*NODE FILE, CONTACT ELEMENTS\nU\n", "")
    (tmp_path / "two_cubes.inp").write_text(deck)
    result = run_job("two_cubes", tmp_path, comm=COMM, progress=False)
    assert result.cel is None and not (tmp_path / "two_cubes.cel").exists()


def test_contact_blocks_end_to_end(tmp_path):
    """Node-based slave, EXPONENTIAL law, amplitude, two steps, FREQUENCY, CONTACT ELEMENTS."""
    result = _run(tmp_path, "blocks")
    deck = read_deck(tmp_path / "blocks.inp")
    step1 = [o for o in result.increments if o.step == 1]
    step2 = [o for o in result.increments if o.step == 2]
    assert step1[-1].step_time == 1.0 and [o.step_time for o in step2] == [0.5, 1.0]
    top = deck.nsets["TOP"]
    first = step1[0]
    assert first.step_time == 0.25
    np.testing.assert_allclose(
        first.displacement_of(top)[:, 2], -0.004 * 0.125, atol=1e-15
    )  # PUSH(0.25)
    for out in (step1[-1], *step2):
        np.testing.assert_allclose(out.displacement_of(top)[:, 2], -0.004, atol=1e-15)

    slaves = set(deck.nsets["SLAVENODES"].tolist())
    for out in result.increments:
        rows = out.contact[0]
        assert rows.pair == "SLAVE-MASTER"
        assert np.all(np.diff(rows.nodes) > 0) and set(rows.nodes.tolist()) <= slaves
        assert out.slave_nodes == set(rows.nodes.tolist()) and len(out.slave_nodes) > 0
        assert np.all(rows.energy > 0) and rows.master_faces.shape == (rows.nodes.size, 4)

    dat = tmp_path / "blocks.dat"
    # FREQUENCY=2: step 1 prints increments 2 and the last; step 2 (FREQUENCY carried) increment 2
    printed = sorted({b.time for b in read_dat(dat)})
    expected = sorted({step1[1].time, step1[-1].time, step2[1].time})
    assert printed == expected
    for time in (step1[1].time, step1[-1].time):
        names = [b.name for b in read_dat(dat) if b.time == time]
        assert names == ["U", "RF", "RF_TOTAL", "CDIS", "CSTR", "CELS", "CNUM", "CELS_TOTAL"]
        base = _blocks(dat, "RF_TOTAL", time)[0].values[0]
        out = next(o for o in result.increments if o.time == time)
        cnum = _blocks(dat, "CNUM", time)[0].values[0, 0]
        assert cnum == out.contact[0].nodes.size
        rows = _blocks(dat, "CSTR", time)[0]
        np.testing.assert_array_equal(rows.labels, out.contact[0].nodes)
        # the base carries the contact load upwards
        assert base[2] > 0
    # step 2 redefines *NODE PRINT: ccx then writes the carried contact prints first
    names = [b.name for b in read_dat(dat) if b.time == step2[1].time]
    assert names == ["CDIS", "CSTR", "CELS", "CNUM", "CELS_TOTAL", "U"]

    elements = read_cel(tmp_path / "blocks.cel")
    numbers = np.array([e.number for e in elements])
    np.testing.assert_array_equal(numbers, deck.num_elements + 1 + np.arange(numbers.size))
    assert elements[0].set == "contactelements_st1_in1_at1_it1"
    assert {e.set.split("_")[1] for e in elements} == {"st1", "st2"}
    assert all(
        e.type == "C3D6" and e.nodes[1] == e.nodes[4] and e.nodes[1] in slaves for e in elements
    )
    assert (tmp_path / "blocks.xdmf").is_file()


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    "name, kind, pattern",
    [
        (
            "err_mixed",
            ValueError,
            r"mixes element types C3D4 \(first at \S*err_mixed.inp:14\), C3D8",
        ),
        (
            "err_unknown_surface",
            DeckError,
            r"err_unknown_surface.inp:34: master surface NOSUCH is not defined",
        ),
    ],
)
def test_bad_decks_fail_clearly(tmp_path, capsys, name, kind, pattern):
    _copy(tmp_path, name)
    with pytest.raises(kind, match=pattern):
        run_job(name, tmp_path, comm=COMM, progress=False)
    assert main(["run", str(tmp_path / f"{name}.inp")]) == 1
    err = capsys.readouterr().err
    assert "*ERROR" in err and "Traceback" not in err
    assert main(["run", str(tmp_path / "missing")]) == 1
    assert main(["frobnicate"]) == 1


def test_non_convergence_keeps_results_and_exits_2(tmp_path, capsys, monkeypatch):
    """Step 2 asks for an impossible residual (R_n = 1e-30, DIRECT): exit 2, step 1 kept.

    Without the absolute residual floor, which lets ccx 2.20 (and the deck runner) converge it.
    """
    monkeypatch.setattr(job_module, "CCX_RESIDUAL_FLOOR", 0.0)
    _copy(tmp_path, "diverge")
    with pytest.raises(JobError, match="step 2, increment 1, attempt 1: no convergence") as error:
        run_job("diverge", tmp_path, comm=COMM, progress=False)
    assert error.value.exit_code == 2
    assert [o.step for o in error.value.result.increments] == [1, 1]
    assert main(["run", str(tmp_path / "diverge")]) == 2
    assert "no convergence" in capsys.readouterr().err
    assert sorted({b.time for b in read_dat(tmp_path / "diverge.dat")}) == [0.5, 1.0]


def test_module_entry_point_reports_errors_without_traceback(tmp_path):
    _copy(tmp_path, "err_unknown_surface")
    command = [sys.executable, "-m", "dolfinx_ntf", "run", "err_unknown_surface"]
    run = subprocess.run(
        command, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False
    )
    assert run.returncode == 1
    assert "err_unknown_surface.inp:34" in run.stderr and "Traceback" not in run.stderr
