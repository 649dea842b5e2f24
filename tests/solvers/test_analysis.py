"""Analyses made of steps (dolfinx_ntf.solvers.analysis): loads, Dirichlet, contact per step."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers import MU, STICK_SLOPE, UPPER_TOP, drag_problem

import dolfinx.fem
import dolfinx.fem.petsc

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial


def _fixed(increments, **kwargs):
    return ntf.StaticStep(initial_increment=1 / increments, fixed=True, **kwargs)


def _automatic(**kwargs):
    return ntf.StaticStep(initial_increment=0.5, **kwargs)


def test_amplitude_and_load_rules():
    amp = ntf.Amplitude([0.0, 1.0, 2.0], [0.0, 2.0, 2.0])
    assert amp(0.5) == 1.0 and amp(5.0) == 2.0
    with pytest.raises(ValueError, match="must not decrease"):
        ntf.Amplitude([1.0, 0.0], [0.0, 1.0])
    with pytest.raises(TypeError, match=r"Constant or dolfinx\.fem\.Function"):
        ntf.Load(1.0, 2.0)


def test_steps_change_friction_remove_and_add_a_pair():
    problem, pressure, _, ft = drag_problem()
    (pair,) = [s.pair for s in problem.states]
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    seen = {}

    def record(name):
        def on_increment(result):
            seen.setdefault(name, []).append((problem.num_springs, ntf.contact_results(problem)[0]))

        return on_increment

    # a prescribed vertical displacement of the top, for the steps without contact
    V = problem.u.function_space
    Vz, _ = compat.component_space(V, 2)
    dofs = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, ft.find(UPPER_TOP))
    lift = dolfinx.fem.Function(Vz)
    lift_bc = dolfinx.fem.dirichletbc(lift, dofs, V.sub(2))

    steps = [
        ntf.AnalysisStep(_fixed(2), loads=[ntf.Load(pressure, 10.0)], name="press"),
        ntf.AnalysisStep(_automatic(on_increment=record("drag")), [ntf.Load(problem.drag, 0.1)]),
        ntf.AnalysisStep(
            _automatic(on_increment=record("mu")),
            [ntf.Load(problem.drag, 0.2)],
            changes=[ntf.ChangeFriction(pair, ntf.Friction(2 * MU, STICK_SLOPE))],
        ),
    ]
    ntf.run_steps(solver, steps)
    _, drag = seen["drag"][-1]
    assert drag.sliding.all()
    # (no friction under the linear law's small tension: friction_in_tension=False)
    np.testing.assert_allclose(
        np.linalg.norm(drag.shear, axis=1), MU * np.maximum(drag.pressure, 0), rtol=1e-10
    )
    _, changed = seen["mu"][-1]
    assert changed.sliding.all()
    np.testing.assert_allclose(
        np.linalg.norm(changed.shear, axis=1), 2 * MU * np.maximum(changed.pressure, 0), rtol=1e-10
    )
    # the state was kept: the slip accumulated over both steps
    assert changed.slip[:, 0].max() > drag.slip[:, 0].max() + 0.05

    # hold the top where it is, remove the pair and lift; then add it back and press again
    top = problem.u.x.array[np.asarray(dofs[0])]
    lift.x.array[np.asarray(dofs[1])] = top
    bcs = [*problem.bcs, lift_bc]
    held = lift.x.array.copy()
    steps = [
        ntf.AnalysisStep(
            _fixed(1, on_increment=record("removed")),
            [ntf.Load(lift, held + 0.01), ntf.Load(pressure, 0.0)],
            bcs=bcs,
            changes=[ntf.RemovePair(pair)],
        ),
        ntf.AnalysisStep(
            _automatic(on_increment=record("added")),
            [ntf.Load(lift, held - 0.002)],
            changes=[ntf.AddPair(pair)],
        ),
    ]
    results = ntf.run_steps(solver, steps)
    assert len(results[0]) == 1 and steps[1].results is results[1]
    # the total time runs on over the steps (each of period 1), the step time restarts
    assert [r.total_time for r in results[0]] == [1.0]
    assert [r.total_time - r.time for r in results[1]] == [1.0] * len(results[1])
    assert [r.total_time for r in results[1]][-1] == 2.0
    assert [n for n, _ in seen["removed"]] == [0]
    assert seen["added"][-1][0] >= 8  # pressed again (the punch top is held tilted)
    # a re-added pair starts afresh (Python default): no slip carried over from before
    added = seen["added"][-1][1]
    assert np.abs(added.slip).max() < 0.05 * np.abs(changed.slip).max()  # measured 1.1 %


def test_linear_overlap_ramp():
    """An initial overlap is taken over the whole first step with overlap_ramp="linear"."""
    results = {}
    for ramp in ("first_increment", "linear"):
        problem, _, _, ft = drag_problem(gap=-1e-3, overlap_ramp=ramp)
        V = problem.u.function_space
        Vz, _ = compat.component_space(V, 2)
        dofs = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, ft.find(UPPER_TOP))
        hold = dolfinx.fem.dirichletbc(dolfinx.fem.Function(Vz), dofs, V.sub(2))
        solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
        forces = []

        def on_increment(result, problem=problem, forces=forces):
            forces.append(ntf.contact_force(problem)[2])

        step = ntf.AnalysisStep(_fixed(4, on_increment=on_increment), bcs=[*problem.bcs, hold])
        ntf.run_steps(solver, [step, ntf.AnalysisStep(_fixed(1, on_increment=on_increment))])
        results[ramp] = np.array(forces)
    first, linear = results["first_increment"], results["linear"]
    assert first[0] > 0
    # ccx's rule: a quarter of the overlap in increment 1, all of it from increment 2 on
    np.testing.assert_allclose(first[1:], first[-1], rtol=1e-6)
    assert first[0] < 0.5 * first[-1]
    # linear: the force grows over step 1 and ends where ccx's does; step 2 keeps it (friction
    # makes the end state depend on the path a little: measured 2.9e-6)
    assert np.all(np.diff(linear[:4]) > 0) and linear[0] == pytest.approx(first[0], rel=1e-6)
    np.testing.assert_allclose(linear[3:], first[-1], rtol=2e-5)


def test_bad_steps():
    problem = drag_problem()[0]
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    with pytest.raises(TypeError, match="procedure must be a dataclass"):
        ntf.run_steps(solver, [ntf.AnalysisStep(procedure=object())])
    other = drag_problem()[0].states[0].pair
    with pytest.raises(ValueError, match="the pair is not in the problem"):
        ntf.run_steps(solver, [ntf.AnalysisStep(changes=[ntf.RemovePair(other)])])


def test_adjust_moves_slave_nodes_onto_the_master_without_strain():
    problem, pressure, _, _ = drag_problem(gap=0.003)
    (state,) = problem.states
    state.pair.adjust = 0.005
    bottom = state.slave.nodes
    before = problem.reference_coordinates[bottom].copy()
    assert np.allclose(before[:, 2], 0.003)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    problem.begin_increment(0.0)
    after = problem.reference_coordinates[bottom]
    np.testing.assert_allclose(after[:, 2], 0.0, atol=1e-15)
    np.testing.assert_array_equal(after[:, :2], before[:, :2])
    assert problem.num_springs == bottom.size
    # the mesh moved with them: the unloaded problem has no residual (no strain)
    x = problem.u.function_space.mesh.geometry.x
    assert np.isclose(x[:, 2], 0.0).sum() > np.isclose(x[:, 2], 0.003).sum()
    b = compat.create_vector(problem.L)
    u = compat.petsc_vector(problem.u)
    problem.form(u)
    problem.F(u, b)
    assert b.norm() < 1e-12
    b.destroy()
    ntf.run_steps(solver, [ntf.AnalysisStep(_fixed(1), [ntf.Load(pressure, 10.0)])])
    assert ntf.contact_force(problem)[2] == pytest.approx(10.0 * 0.6 * 0.6, rel=1e-8)
    with pytest.raises(ValueError, match="adjust must be a finite distance"):
        ntf.ContactPair(state.pair.slave, state.pair.master, state.pair.interaction, adjust=-1.0)
