"""Contact on several processes gives the serial answer (docs/method.md §14).

Every test compares with the same problem solved on ``COMM_SELF`` in the same run. ``make
test-here`` runs this file on 2 processes and again on 3; in serial the comparisons are trivial.
"""

import functools
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np
import pytest
from conftest import (
    LOWER_BOTTOM,
    LOWER_TOP,
    PUNCH,
    UPPER,
    UPPER_BOTTOM,
    UPPER_TOP,
    elastic_residual,
    punch_problem,
    two_blocks,
)

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact import problem as problem_module
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
LOAD = 20.0


def _bodies(x):
    """The lower block on rank 0, the upper (slave) block on the others (sliced along x)."""
    others = max(COMM.size - 1, 1)
    upper = np.minimum(1 + (x[:, 0] * others).astype(int), COMM.size - 1)
    return np.where(x[:, 2] > 0.0, upper, 0)


def _cut(x):
    """Slices along x: every cut crosses the contact zone."""
    return np.minimum((x[:, 0] * COMM.size).astype(int), COMM.size - 1)


def _idle(x):
    """The last rank holds the bottom of the lower block only: no slave or master node."""
    if COMM.size == 1:
        return np.zeros(x.shape[0], dtype=int)
    others = max(COMM.size - 1, 1)
    return np.where(x[:, 2] < -0.5, COMM.size - 1, np.where(x[:, 2] > 0.0, 1 % others, 0))


def _empty(x):
    """The last rank holds no cell at all (dolfinx 0.5.2's ``collapse`` crashes there)."""
    others = max(COMM.size - 1, 1)
    return np.minimum((x[:, 0] * others).astype(int), others - 1)


PARTITIONS = {"graph": None, "bodies": _bodies, "cut": _cut, "idle": _idle, "empty": _empty}


@dataclass
class Run:
    X: np.ndarray  # reference positions of all nodes, sorted
    u: np.ndarray  # displacements in the same order
    iterations: list[tuple[int, int]]  # Newton iterations and springs of every increment
    pairings: list[np.ndarray]  # per pairing: (slave position, master face centre) of every spring
    springs: np.ndarray  # final springs: slave position, area, pressure, clearance
    force: np.ndarray
    mallocs: float
    rebuilds: int


def _sorted(comm, rows):
    rows = np.vstack(comm.allgather(rows))
    return rows[np.lexsort(np.round(rows, 9).T[::-1])]


def solve_step(comm, problem, pressure, u):
    """The punch's two increments of ``LOAD``: (iterations and springs per increment, sorted
    reference positions and displacements of the owned nodes, this process's contact table)."""
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    results = step.run(solver, u)
    solver.destroy()
    owned = u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned]
    nodes = _sorted(comm, np.hstack([X, u.x.array.reshape(-1, 3)[:owned]]))
    increments = [(r.iterations, r.springs) for r in results]
    return increments, nodes, ntf.contact_results(problem)[0]


def _solve(comm, cell, partition, degree=1, **options):
    problem, pressure, _ = punch_problem(
        cell, comm=comm, partition=partition, degree=degree, **options
    )
    pairings = []

    def record(p):
        x = p.current_coordinates()
        rows = [
            np.hstack([x[s.element_nodes[:, -1]], x[s.element_nodes[:, :-1]].mean(axis=1)])
            for s in p.states
        ]
        pairings.append(_sorted(comm, np.vstack(rows)))

    problem.pairing_callbacks.append(record)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned]
    nodes = _sorted(comm, np.hstack([X, problem.u.x.array.reshape(-1, 3)[:owned]]))
    table = ntf.contact_results(problem)[0]
    springs = _sorted(
        comm, np.column_stack([table.position, table.area, table.pressure, table.clearance])
    )
    run = Run(
        nodes[:, :3],
        nodes[:, 3:],
        [(r.iterations, r.springs) for r in results],
        pairings,
        springs,
        ntf.contact_force(problem),
        problem.matrix.getInfo()["mallocs"],
        problem.assembler.matrix_rebuilds,
    )
    solver.destroy()
    problem.destroy()
    return run


@functools.lru_cache
def _serial(cell, degree=1, **options):
    return _solve(MPI.COMM_SELF, cell, None, degree, **options)


def _assert_same(run, serial):
    assert run.iterations == serial.iterations
    assert len(run.pairings) == len(serial.pairings)
    for i, (a, b) in enumerate(zip(run.pairings, serial.pairings)):
        assert a.shape == b.shape, f"pairing {i}: {a.shape[0]} springs, serial {b.shape[0]}"
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.X, serial.X, rtol=0, atol=1e-14)
    np.testing.assert_allclose(run.u, serial.u, rtol=0, atol=1e-10 * np.abs(serial.u).max())
    assert run.springs.shape == serial.springs.shape
    # positions, areas (complete at partition cuts), pressures and clearances of every spring
    np.testing.assert_allclose(run.springs, serial.springs, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(run.force, serial.force, atol=1e-10 * np.abs(serial.force).max())
    assert serial.springs.shape[0] > 0 and serial.force[2] > 0


@pytest.mark.parametrize("partition", PARTITIONS)
@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_punch_gives_the_serial_answer(cell, partition):
    run = _solve(COMM, cell, PARTITIONS[partition])
    _assert_same(run, _serial(cell))
    assert run.mallocs == 0  # every coupling was preallocated, on the process owning its row


def test_quadratic_tetrahedra_cut_through_the_contact_zone():
    _assert_same(_solve(COMM, "tetrahedron", _cut, degree=2), _serial("tetrahedron", 2))


@pytest.mark.parametrize(
    "options", [{"linearize_area": True}, {"symmetric": True, "walk_from_previous_face": False}]
)
def test_problem_options_give_the_serial_answer(options):
    """Area linearization couples halo slave-face nodes; CalculiX's search and tangent."""
    run = _solve(COMM, "hexahedron", _cut, **options)
    _assert_same(run, _serial("hexahedron", **options))
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
        areas = problem_module._slave_areas(slave, problem.current_coordinates())
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
    problem, _, _ = punch_problem(comm=COMM, partition=_idle)
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
        return iterations, converged, _sorted(comm, rows)

    parallel, serial = solve(COMM), solve(MPI.COMM_SELF)
    assert parallel[:2] == serial[:2] and parallel[1]
    np.testing.assert_allclose(parallel[2], serial[2], rtol=0, atol=1e-10 * np.abs(serial[2]).max())


def test_a_pair_error_found_on_one_rank_fails_on_all():
    """Slave nodes inside the master surface, owned by one rank only: every rank raises."""
    mesh, _, ft = two_blocks(COMM, partition=_bodies)
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
    problem, pressure, _ = punch_problem(comm=COMM, partition=_cut)
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
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "demos" / "punch.py"
    spec = importlib.util.spec_from_file_location("_demo_punch_mpi", path)
    demo = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(demo)
    folder = COMM.bcast(str(tmp_path_factory.mktemp("demo")) if COMM.rank == 0 else None)
    summary = demo.main(["--coarse", "--quiet", "--output", folder])
    assert summary["passed"]
    assert summary["springs"] == [25, 25, 25, 25]
    assert summary["vertical_error"] < 1e-8 and summary["reaction_error"] < 1e-8
    assert summary["contact_area"] == pytest.approx(40 * 40, rel=1e-3)


@pytest.mark.parametrize("partition", ["graph", "cut"])
def test_node_based_slave_gives_the_serial_answer(partition):
    """A node-based slave surface whose vertices each process finds among its own (ghosts too)."""

    def solve(comm, owners):
        mesh, cell_tags, ft = two_blocks(comm, upper=PUNCH, partition=owners)
        V = compat.vector_space(mesh, "Lagrange", 1)
        u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
        pressure = dolfinx.fem.Constant(mesh, 0.0)
        upper = compat.incident_entities(mesh, cell_tags.find(UPPER), 3, 0)
        bottom = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[2], 0.0))
        slave = ntf.NodeSurface(np.intersect1d(upper, bottom))
        law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
        pair = ntf.ContactPair(slave, ntf.FacetSurface(ft, LOWER_TOP), law)
        clamp = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
        bcs = [
            dolfinx.fem.dirichletbc(np.zeros(3), clamp, V),
            component_bc(V, 0, ft.find(UPPER_TOP)),
            component_bc(V, 1, ft.find(UPPER_TOP)),
        ]
        problem = ntf.ContactProblem(elastic_residual(u, v, ft, pressure), u, [pair], bcs)
        solver = ntf.ContactNewtonSolver(comm, problem)
        results = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, u)
        owned = V.dofmap.index_map.size_local
        nodes = _sorted(
            comm,
            np.hstack([problem.reference_coordinates[:owned], u.x.array.reshape(-1, 3)[:owned]]),
        )
        table = ntf.contact_results(problem)[0]
        springs = _sorted(comm, np.column_stack([table.position, table.area, table.pressure]))
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
