"""Runs on several processes compared with the same run on ``COMM_SELF`` (docs/method.md §14).

Partitions of the two blocks (``PARTITIONS``: dolfinx's graph partitioner, the bodies apart,
slices along x, an idle last process, an empty last process), the punch pressed in two increments
and the frictional press-drag analysis, each with its serial run (cached) and the comparison that
asserts both give the same answer.
"""

import functools
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx_ntf as ntf

from .blocks import (
    LOWER_TOP,
    MU,
    PRESSURE,
    PUNCH,
    STICK_SLOPE,
    UPPER_BOTTOM,
    displacement_fields,
    drag_conditions,
    elastic_residual,
    punch_problem,
    two_blocks,
)

COMM = MPI.COMM_WORLD
LOAD = 20.0


def by_body(x):
    """The lower block on rank 0, the upper (slave) block on the others (sliced along x)."""
    others = max(COMM.size - 1, 1)
    upper = np.minimum(1 + (x[:, 0] * others).astype(int), COMM.size - 1)
    return np.where(x[:, 2] > 0.0, upper, 0)


def cut_along_x(x):
    """Slices along x: every cut crosses the contact zone."""
    return np.minimum((x[:, 0] * COMM.size).astype(int), COMM.size - 1)


def idle_last(x):
    """The last rank holds the bottom of the lower block only: no slave or master node."""
    if COMM.size == 1:
        return np.zeros(x.shape[0], dtype=int)
    others = max(COMM.size - 1, 1)
    return np.where(x[:, 2] < -0.5, COMM.size - 1, np.where(x[:, 2] > 0.0, 1 % others, 0))


def empty_last(x):
    """The last rank holds no cell at all (dolfinx 0.5.2's ``collapse`` crashes there)."""
    others = max(COMM.size - 1, 1)
    return np.minimum((x[:, 0] * others).astype(int), others - 1)


PARTITIONS = {
    "graph": None,
    "bodies": by_body,
    "cut": cut_along_x,
    "idle": idle_last,
    "empty": empty_last,
}


@dataclass
class PunchRun:
    """What ``solve_punch`` compares with the serial run."""

    X: np.ndarray  # reference positions of all nodes, sorted
    u: np.ndarray  # displacements in the same order
    iterations: list[tuple[int, int]]  # Newton iterations and springs of every increment
    pairings: list[np.ndarray]  # per pairing: (slave position, master face centre) of every spring
    springs: np.ndarray  # final springs: slave position, area, pressure, clearance
    force: np.ndarray
    mallocs: float
    rebuilds: int


def sorted_rows(comm, rows):
    """The rows of every process, gathered and sorted by their rounded values (any partition)."""
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
    nodes = sorted_rows(comm, np.hstack([X, u.x.array.reshape(-1, 3)[:owned]]))
    increments = [(r.iterations, r.springs) for r in results]
    return increments, nodes, ntf.contact_results(problem)[0]


def solve_step_springs(comm, problem, pressure, u):
    """``solve_step``; the final springs' position, area and pressure sorted over all processes."""
    increments, nodes, table = solve_step(comm, problem, pressure, u)
    springs = sorted_rows(comm, np.column_stack([table.position, table.area, table.pressure]))
    return increments, nodes, springs


def solve_punch(comm, cell, partition, degree=1, **options):
    """The punch's two increments of ``LOAD`` on ``comm``, recorded for ``assert_same_punch``."""
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
        pairings.append(sorted_rows(comm, np.vstack(rows)))

    problem.pairing_callbacks.append(record)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned]
    nodes = sorted_rows(comm, np.hstack([X, problem.u.x.array.reshape(-1, 3)[:owned]]))
    table = ntf.contact_results(problem)[0]
    springs = sorted_rows(
        comm, np.column_stack([table.position, table.area, table.pressure, table.clearance])
    )
    run = PunchRun(
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
def serial_punch(cell, degree=1, **options):
    """``solve_punch`` on ``COMM_SELF`` (cached: one serial run per case and process)."""
    return solve_punch(MPI.COMM_SELF, cell, None, degree, **options)


def assert_same_punch(run, serial):
    """The parallel run gives the serial pairings, displacements, springs and force."""
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


@dataclass
class FrictionRun:
    """What ``friction_analysis`` compares with the serial run."""

    increments: list[tuple[int, int]]  # Newton iterations and springs of every increment
    iterates: list[np.ndarray]  # displacement at every evaluation of the springs
    pairings: list[np.ndarray]  # per pairing: (slave position, master face centre) of every spring
    u: np.ndarray  # final displacements, sorted by reference position
    springs: np.ndarray  # final springs: position, pressure, shear, slip, sliding, friction energy
    outputs: list[np.ndarray]  # the springs' table after every increment of the drag steps
    mallocs: float


def owned_rows(comm, problem, values):
    """(reference position, values) of the owned nodes of every process, sorted by position."""
    owned = problem.u.function_space.dofmap.index_map.size_local
    rows = np.hstack([problem.reference_coordinates[:owned], values[:owned]])
    return sorted_rows(comm, rows)


def friction_table(comm, problem):
    """Position, pressure, shear, slip, sliding and friction energy of every spring, sorted."""
    t = ntf.contact_results(problem)[0]
    columns = [t.position, t.pressure, t.shear, t.slip, t.sliding, t.friction_energy]
    return sorted_rows(comm, np.column_stack(columns))


def friction_analysis(comm, partition, cell="hexahedron", **options):
    """Press, drag (stick, then slip), then drag on with twice the friction coefficient."""
    mesh, _, ft = two_blocks(comm, upper=PUNCH, cell=cell, partition=partition)
    V, u, v, pressure = displacement_fields(mesh)
    bcs, drag = drag_conditions(V, ft)
    interaction = ntf.SurfaceInteraction(
        ntf.LinearLaw.with_ccx_defaults(1000.0), ntf.Friction(MU, STICK_SLOPE)
    )
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), interaction
    )
    problem = ntf.ContactProblem(elastic_residual(u, v, ft, pressure), u, [pair], bcs, **options)

    iterates, pairings, outputs = [], [], []
    form = problem.form

    def recorded_form(x):  # every rank evaluates together: the gathers are collective
        form(x)
        iterates.append(owned_rows(comm, problem, problem.u.x.array.reshape(-1, 3))[:, 3:])

    def record_pairing(p):
        x = p.current_coordinates()
        nodes = p.states[0].element_nodes
        rows = np.hstack([x[nodes[:, -1]], x[nodes[:, :-1]].mean(axis=1)])
        pairings.append(sorted_rows(comm, rows))

    problem.form = recorded_form
    problem.pairing_callbacks.append(record_pairing)
    solver = ntf.ContactNewtonSolver(comm, problem)

    def step(increment, **kwargs):
        def on_increment(result):
            outputs.append(friction_table(comm, problem))

        return ntf.StaticStep(
            lambda t: None, initial_increment=increment, on_increment=on_increment, **kwargs
        )

    steps = [
        ntf.AnalysisStep(step(0.5, fixed=True), [ntf.Load(pressure, PRESSURE)], name="press"),
        ntf.AnalysisStep(step(0.25), [ntf.Load(drag[0], 0.05)], name="drag"),
        ntf.AnalysisStep(
            step(0.5),
            [ntf.Load(drag[0], 0.07), ntf.Load(drag[1], -0.01)],
            changes=[ntf.ChangeFriction(pair, ntf.Friction(2 * MU, STICK_SLOPE))],
            name="mu",
        ),
    ]
    results = ntf.run_steps(solver, steps)
    run = FrictionRun(
        [(r.iterations, r.springs) for step_results in results for r in step_results],
        iterates,
        pairings,
        owned_rows(comm, problem, u.x.array.reshape(-1, 3))[:, 3:],
        friction_table(comm, problem),
        outputs,
        problem.matrix.getInfo()["mallocs"],
    )
    solver.destroy()
    problem.destroy()
    return run


@functools.lru_cache
def serial_friction_analysis(cell="hexahedron", **options):
    """``friction_analysis`` on ``COMM_SELF`` (cached)."""
    return friction_analysis(MPI.COMM_SELF, None, cell, **options)


def assert_same_friction(run, serial):
    """The parallel analysis gives the serial iterates, pairings and friction outputs."""
    assert run.increments == serial.increments
    assert len(run.iterates) == len(serial.iterates)
    scale = np.abs(serial.u).max()
    for i, (a, b) in enumerate(zip(run.iterates, serial.iterates)):
        assert np.abs(a - b).max() <= 1e-10 * scale, f"evaluation {i}"
    assert len(run.pairings) == len(serial.pairings)
    for i, (a, b) in enumerate(zip(run.pairings, serial.pairings)):
        assert a.shape == b.shape, f"pairing {i}: {a.shape[0]} springs, serial {b.shape[0]}"
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(run.u, serial.u, rtol=0, atol=1e-10 * scale)
    assert len(run.outputs) == len(serial.outputs)
    for a, b in zip([*run.outputs, run.springs], [*serial.outputs, serial.springs]):
        assert a.shape == b.shape
        # stick or slip of every spring exactly; values to round-off of their column's scale
        np.testing.assert_array_equal(a[:, 10], b[:, 10])
        error = (np.abs(a - b) / np.maximum(np.abs(b).max(axis=0), 1e-300)).max(axis=0)
        assert np.all(error <= 1e-9), f"largest differences by column: {error}"
