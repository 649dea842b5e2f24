"""Friction on several processes gives the serial answer (docs/method.md §14.6).

A punch pressed onto a block, dragged (stick, then slip), then dragged on with a larger friction
coefficient (``ChangeFriction``), each step of several increments. Every run is compared with the
same analysis solved on ``COMM_SELF`` in the same run: the Newton iterates, iteration counts,
pairings and the friction outputs of every spring. In serial the comparisons are trivial.
"""

import functools
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np
import pytest
from conftest import LOWER_BOTTOM, LOWER_TOP, PUNCH, UPPER_BOTTOM, UPPER_TOP, elastic_residual
from conftest import two_blocks as blocks
from test_parallel import PARTITIONS, _cut, _sorted

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
MU, STICK_SLOPE, PRESSURE = 0.2, 500.0, 10.0


@dataclass
class Run:
    increments: list[tuple[int, int]]  # Newton iterations and springs of every increment
    iterates: list[np.ndarray]  # displacement at every evaluation of the springs
    pairings: list[np.ndarray]  # per pairing: (slave position, master face centre) of every spring
    u: np.ndarray  # final displacements, sorted by reference position
    springs: np.ndarray  # final springs: position, pressure, shear, slip, sliding, friction energy
    outputs: list[np.ndarray]  # the springs' table after every increment of the drag steps
    mallocs: float


def _owned_rows(comm, problem, values):
    """(reference position, values) of the owned nodes of every process, sorted by position."""
    owned = problem.u.function_space.dofmap.index_map.size_local
    rows = np.hstack([problem.reference_coordinates[:owned], values[:owned]])
    return _sorted(comm, rows)


def _table(comm, problem):
    t = ntf.contact_results(problem)[0]
    columns = [t.position, t.pressure, t.shear, t.slip, t.sliding, t.friction_energy]
    return _sorted(comm, np.column_stack(columns))


def _analysis(comm, partition, cell="hexahedron", **options):
    """Press, drag (stick, then slip), then drag on with twice the friction coefficient."""
    mesh, _, ft = blocks(comm, upper=PUNCH, cell=cell, partition=partition)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), bottom, V)]
    drag = []
    for component in (0, 1):
        Vc, _ = compat.component_space(V, component)
        dofs = dolfinx.fem.locate_dofs_topological((V.sub(component), Vc), 2, ft.find(UPPER_TOP))
        drag.append(dolfinx.fem.Function(Vc))
        bcs.append(dolfinx.fem.dirichletbc(drag[-1], dofs, V.sub(component)))
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
        iterates.append(_owned_rows(comm, problem, problem.u.x.array.reshape(-1, 3))[:, 3:])

    def record_pairing(p):
        x = p.current_coordinates()
        nodes = p.states[0].element_nodes
        rows = np.hstack([x[nodes[:, -1]], x[nodes[:, :-1]].mean(axis=1)])
        pairings.append(_sorted(comm, rows))

    problem.form = recorded_form
    problem.pairing_callbacks.append(record_pairing)
    solver = ntf.ContactNewtonSolver(comm, problem)

    def step(increment, **kwargs):
        def on_increment(result):
            outputs.append(_table(comm, problem))

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
    run = Run(
        [(r.iterations, r.springs) for step_results in results for r in step_results],
        iterates,
        pairings,
        _owned_rows(comm, problem, u.x.array.reshape(-1, 3))[:, 3:],
        _table(comm, problem),
        outputs,
        problem.matrix.getInfo()["mallocs"],
    )
    solver.destroy()
    problem.destroy()
    return run


@functools.lru_cache
def _serial(cell="hexahedron", **options):
    return _analysis(MPI.COMM_SELF, None, cell, **options)


def _assert_same(run, serial):
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


def _mixed(serial):
    """The serial analysis really sticks and slips."""
    sliding = [table[:, 10] for table in serial.outputs]
    assert any(s.size and not s.any() for s in sliding)  # all springs stick (press, early drag)
    assert any(s.size and s.all() for s in sliding)  # all slip (late drag)
    assert serial.springs.shape[0] >= 8 and np.abs(serial.springs[:, 4:7]).max() > 0.5


@pytest.mark.parametrize("partition", PARTITIONS)
def test_frictional_analysis_gives_the_serial_answer(partition):
    """Every partition, one body per process and an idle process included; no hang."""
    serial = _serial()
    _mixed(serial)
    run = _analysis(COMM, PARTITIONS[partition])
    _assert_same(run, serial)
    assert run.mallocs == 0


@pytest.mark.parametrize(
    "options",
    [
        {"cell": "tetrahedron"},
        {
            "friction_tangent": "ccx",
            "reset_friction_on_separation": False,
            "friction_in_tension": True,
            "symmetric": True,
        },
    ],
    ids=["tetrahedra", "calculix-options"],
)
def test_friction_options_give_the_serial_answer(options):
    """Tetrahedra; CalculiX's tangent, stale state and friction in tension (the deck runner's)."""
    options = dict(options)
    cell = options.pop("cell", "hexahedron")
    run = _analysis(COMM, _cut, cell, **options)
    _assert_same(run, _serial(cell, **options))
