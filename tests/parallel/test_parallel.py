"""Contact on several processes gives the serial answer (docs/method.md §14).

Every test compares with the same problem solved on ``COMM_SELF`` in the same run. ``make
test-here`` runs this file on 2 processes and again on 3; in serial the comparisons are trivial.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, PUNCH, UPPER, UPPER_BOTTOM, punch_bulk, punch_problem, two_blocks
from helpers.demos import load_demo
from helpers.serial_answer import (
    LOAD,
    PARTITIONS,
    assert_same_punch,
    by_body,
    cut_along_x,
    idle_last,
    serial_punch,
    solve_punch,
    sorted_rows,
)

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact import pairing as pairing_module
from dolfinx_ntf.fem.elasticity import small_strain_stress

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


@pytest.mark.parametrize("partition", PARTITIONS)
@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_punch_gives_the_serial_answer(cell, partition):
    run = solve_punch(COMM, cell, PARTITIONS[partition])
    assert_same_punch(run, serial_punch(cell))
    assert run.mallocs == 0  # every coupling was preallocated, on the process owning its row


def test_quadratic_tetrahedra_cut_through_the_contact_zone():
    assert_same_punch(
        solve_punch(COMM, "tetrahedron", cut_along_x, degree=2), serial_punch("tetrahedron", 2)
    )


@pytest.mark.parametrize(
    "options", [{"linearize_area": True}, {"symmetric": True, "walk_from_previous_face": False}]
)
def test_problem_options_give_the_serial_answer(options):
    """Area linearization couples halo slave-face nodes; CalculiX's search and tangent."""
    run = solve_punch(COMM, "hexahedron", cut_along_x, **options)
    assert_same_punch(run, serial_punch("hexahedron", **options))
    assert run.mallocs == 0


@pytest.mark.parametrize("partition", PARTITIONS)
def test_each_process_receives_the_slave_faces_of_its_nodes(partition):
    """docs/method.md §14.1: the owned slave nodes and exactly the slave faces (of any process)
    holding one of them, so that spring areas at partition cuts equal the serial ones."""

    def faces_and_areas(comm, owners):
        problem, _, _ = punch_problem(comm=comm, partition=owners)
        slave = problem.states[0].slave
        x = np.round(problem.current_coordinates(), 9)
        owned = problem.u.function_space.dofmap.index_map.size_local
        areas = pairing_module.slave_areas(slave, problem.current_coordinates())
        problem.destroy()
        assert np.all(slave.nodes < owned)
        faces = {tuple(sorted(map(tuple, x[f]))) for f in slave.faces.faces}
        return faces, dict(zip(map(tuple, x[slave.nodes]), areas))

    faces, areas = faces_and_areas(COMM, PARTITIONS[partition])
    serial_faces, serial_areas = faces_and_areas(MPI.COMM_SELF, None)
    assert sum(COMM.allgather(len(areas))) == len(serial_areas)  # each slave node once
    expected = {f for f in serial_faces if any(node in areas for node in f)}
    assert faces == expected  # no face without an owned slave node, none missing
    for node, area in areas.items():
        assert area == pytest.approx(serial_areas[node], rel=1e-12)


def test_idle_rank_holds_no_contact_node():
    """The partition leaves the last rank owning no contact node (when there are >= 2)."""
    problem, _, _ = punch_problem(comm=COMM, partition=idle_last)
    state = problem.states[0]
    owned = problem.u.function_space.dofmap.index_map.size_local
    held = COMM.allgather(
        (state.slave.nodes.size, int(np.count_nonzero(state.master_faces.nodes < owned)))
    )
    problem.destroy()
    if COMM.size > 1:
        assert held[-1] == (0, 0)
    assert sum(h[0] for h in held) == 16  # the punch's 4 x 4 bottom nodes, each once


def test_box_without_pairs():
    """No contact pairs on a dolfinx box: the contact solver equals the serial solve."""

    def solve(comm):
        mesh = dolfinx.mesh.create_box(
            comm, [[0, 0, 0], [1, 1, 1]], [3, 3, 3], dolfinx.mesh.CellType.tetrahedron
        )
        V = compat.vector_space(mesh, "Lagrange", 1)
        u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
        gravity = dolfinx.fem.Constant(mesh, np.array([0.0, 0.0, -1.0]))
        F = ufl.inner(small_strain_stress(u, 1000.0, 0.3), ufl.grad(v)) * ufl.dx
        F -= ufl.inner(gravity, v) * ufl.dx
        facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 0))
        dofs = dolfinx.fem.locate_dofs_topological(V, 2, facets)
        problem = ntf.ContactProblem(F, u, [], [dolfinx.fem.dirichletbc(np.zeros(3), dofs, V)])
        solver = ntf.ContactNewtonSolver(comm, problem)
        iterations, converged = solver.solve(u)
        owned = V.dofmap.index_map.size_local
        rows = np.hstack([problem.reference_coordinates[:owned], u.x.array.reshape(-1, 3)[:owned]])
        solver.destroy()
        problem.destroy()
        return iterations, converged, sorted_rows(comm, rows)

    parallel, serial = solve(COMM), solve(MPI.COMM_SELF)
    assert parallel[:2] == serial[:2] and parallel[1]
    np.testing.assert_allclose(parallel[2], serial[2], rtol=0, atol=1e-10 * np.abs(serial[2]).max())


def test_a_pair_error_found_on_one_rank_fails_on_all():
    """Slave nodes inside the master surface, owned by one rank only: every rank raises."""
    mesh, _, ft = two_blocks(COMM, partition=by_body)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u = dolfinx.fem.Function(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
    surface = ntf.FacetSurface(ft, UPPER_BOTTOM)
    pair = ntf.ContactPair(surface, ntf.FacetSurface(ft, [LOWER_TOP, UPPER_BOTTOM]), law)
    with pytest.raises(ValueError, match="belong to both the slave and the master"):
        ntf.ContactProblem(F, u, [pair])


def test_writer_and_fields_in_parallel(tmp_path_factory):
    """The contact fields hold the springs' values at owned and ghost nodes alike."""
    problem, pressure, _ = punch_problem(comm=COMM, partition=cut_along_x)
    solver = ntf.ContactNewtonSolver(COMM, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
    folder = COMM.bcast(str(tmp_path_factory.mktemp("out")) if COMM.rank == 0 else None)
    with ntf.ContactWriter(problem, f"{folder}/punch.xdmf") as writer:
        writer.write(1.0)
        table = ntf.contact_results(problem)[0]
        values = dict(zip(map(tuple, np.round(table.position, 9)), table.pressure))
        values = {k: v for part in COMM.allgather(values) for k, v in part.items()}
        x = problem.current_coordinates()[: problem.u.x.array.size // 3]
        q = writer.fields._q_of_node
        for node in problem.states[0].slave.nodes:  # owned: the rank's own springs
            assert writer.pressure.x.array[q[node]] == values.get(tuple(np.round(x[node], 9)), 0)
        slave = np.flatnonzero(np.isclose(problem.reference_coordinates[: x.shape[0], 2], 0.0))
        slave = slave[np.isin(slave, problem.states[0].slave.nodes, invert=True)]
        for node in slave:  # ghosts at the cut: the owner's value
            key = tuple(np.round(x[node], 9))
            if key in values:
                assert writer.pressure.x.array[q[node]] == values[key]
    solver.destroy()
    problem.destroy()


def test_punch_demo_in_parallel(tmp_path_factory):
    """The demo's checks pass with the serial figures (tests/test_demos.py) on any process count."""
    demo = load_demo("punch")
    folder = COMM.bcast(str(tmp_path_factory.mktemp("demo")) if COMM.rank == 0 else None)
    summary = demo.main(["--coarse", "--quiet", "--output", folder])
    assert summary["passed"]
    assert summary["springs"] == [25, 25, 25, 25]
    assert summary["vertical_error"] < 1e-8 and summary["reaction_error"] < 1e-8
    assert summary["contact_area"] == pytest.approx(40 * 40, rel=1e-3)


def test_hot_block_demo_in_parallel(tmp_path_factory):
    """The coupled demo's checks (force, heat balances, jumps, bounds) on any process count."""
    demo = load_demo("hot_block")
    folder = COMM.bcast(str(tmp_path_factory.mktemp("demo")) if COMM.rank == 0 else None)
    summary = demo.main(["--coarse", "--quiet", "--output", folder])
    assert summary["passed"]
    assert summary["springs"] == 25 and summary["increments"] == 4
    assert summary["force_error"] < 1e-8 and summary["jump_error"] < 1e-8
    assert summary["balance_top"] <= summary["balance_bound"] < 1e-8
    # The steady flow is the serial one (measured 49.743037 W serially).
    assert summary["heat_in_top"] == pytest.approx(49.743037, rel=1e-6)


def test_plastic_indentation_demo_in_parallel(tmp_path_factory):
    """The indentation demo's checks (equilibrium, dent, elastic control) on any process count."""
    demo = load_demo("plastic_indentation")
    folder = COMM.bcast(str(tmp_path_factory.mktemp("demo")) if COMM.rank == 0 else None)
    summary = demo.main(["--coarse", "--quiet", "--output", folder])
    assert summary["passed"]
    assert summary["equilibrium_error"] < 1e-8 and summary["final_springs"] == 0
    # The serial dent (measured 0.17641 mm serially) and peak force (6632.06 N).
    assert summary["residual_dent"] == pytest.approx(0.17641, rel=1e-4)
    assert summary["peak_force"] == pytest.approx(6632.06, rel=1e-5)


@pytest.mark.parametrize("partition", ["graph", "cut"])
def test_node_based_slave_gives_the_serial_answer(partition):
    """A node-based slave surface whose vertices each process finds among its own (ghosts too)."""

    def solve(comm, owners):
        mesh, cell_tags, ft = two_blocks(comm, upper=PUNCH, partition=owners)
        u, F, pressure, bcs = punch_bulk(mesh, ft)
        V = u.function_space
        upper = compat.incident_entities(mesh, cell_tags.find(UPPER), 3, 0)
        bottom = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[2], 0.0))
        slave = ntf.NodeSurface(np.intersect1d(upper, bottom))
        law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
        pair = ntf.ContactPair(slave, ntf.FacetSurface(ft, LOWER_TOP), law)
        problem = ntf.ContactProblem(F, u, [pair], bcs)
        solver = ntf.ContactNewtonSolver(comm, problem)
        results = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, u)
        owned = V.dofmap.index_map.size_local
        nodes = sorted_rows(
            comm,
            np.hstack([problem.reference_coordinates[:owned], u.x.array.reshape(-1, 3)[:owned]]),
        )
        table = ntf.contact_results(problem)[0]
        springs = sorted_rows(comm, np.column_stack([table.position, table.area, table.pressure]))
        out = ([(r.iterations, r.springs) for r in results], nodes, springs)
        solver.destroy()
        problem.destroy()
        return out

    (iterations, nodes, springs), serial = (
        solve(COMM, PARTITIONS[partition]),
        solve(MPI.COMM_SELF, None),
    )
    assert iterations == serial[0]
    np.testing.assert_allclose(nodes, serial[1], rtol=0, atol=1e-10 * np.abs(serial[1]).max())
    np.testing.assert_allclose(springs, serial[2], rtol=1e-10, atol=1e-12)
    assert serial[2].shape[0] == 16
