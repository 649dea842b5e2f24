"""Friction of 2D node-to-segment springs: a block pressed onto a fixed flat line, then dragged.

The lower block's top is clamped, so every master edge stays on the x-axis and every spring's
normal is exactly (0, 1): in slip each spring carries |F_T| = mu F_N along x, so the contact force
on the upper block satisfies F_x = mu F_y to round-off, and F_y is the pressure times the width
(the block has no other vertical support). In stick F_x stays below mu F_y. Plane strain (P1 and
P2) and axisymmetric; CHANGE FRICTION between steps; the assembled Jacobian against central
differences of the residual; on several processes the serial answer.
"""

from __future__ import annotations

import functools

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import (
    DRAG_SPAN,
    MU,
    PARTITIONS,
    PRESSURE,
    STICK_SLOPE,
    UPPER_TOP,
    drag_problem,
    press_and_drag,
)
from helpers.jacobian_check import directional_derivative
from helpers.serial_answer import sorted_rows

import dolfinx_ntf as ntf

WIDTH = DRAG_SPAN[1] - DRAG_SPAN[0]


def _drag(distance, *, degree=1, axisymmetric=False, increments=2, steps_of=None, **options):
    problem, pressure, drag, ft = drag_problem(degree=degree, axisymmetric=axisymmetric, **options)
    steps = steps_of(problem) if steps_of else ()
    results = press_and_drag(problem, pressure, drag, distance, increments=increments, steps=steps)
    return problem, results, ft


def _sum(comm, values):
    return comm.allreduce(np.asarray(values).sum(axis=0), op=MPI.SUM)


@pytest.mark.serial
@pytest.mark.parametrize("degree", [1, 2])
def test_slip_transmits_mu_times_the_normal_force(degree):
    """All springs slide: F_x = mu F_y to round-off, F_y = p w; the top's reaction balances F_x.

    P2: the trailing corner node lifts (the law's tension, no friction in tension), so the
    Coulomb sum runs over the springs in compression.
    """
    problem, results, ft = _drag(0.02, degree=degree, increments=4)
    (res,) = ntf.contact_results(problem)
    assert res.node.size == 3 * degree + 1 and res.sliding.all()
    assert res.shear.shape == (res.node.size, 2) and res.slip.shape == (res.node.size, 2)
    np.testing.assert_allclose(res.normal, np.tile([0.0, 1.0], (res.node.size, 1)), atol=1e-14)
    pressing = res.normal_force > 0
    assert np.count_nonzero(pressing) >= res.node.size - 1
    np.testing.assert_allclose(
        np.abs(res.shear[pressing, 0]), MU * res.pressure[pressing], rtol=1e-12
    )
    np.testing.assert_array_equal(res.shear[~pressing], 0.0)
    assert np.all(np.abs(res.shear[:, 1]) <= 1e-14 * np.abs(res.shear[:, 0]).max())
    assert np.all(res.slip[:, 0] > 0.0)
    force = ntf.contact_force(problem)  # on the upper block
    assert force[1] == pytest.approx(PRESSURE * WIDTH, rel=1e-8)  # Newton's tolerance
    compression = res.normal_force[pressing].sum()
    assert -force[0] == pytest.approx(MU * compression, rel=1e-12)  # Coulomb, to round-off
    if degree == 1:
        assert compression == pytest.approx(force[1], rel=1e-14)
    top = ntf.reaction(problem, ft.find(UPPER_TOP))
    assert top[0] == pytest.approx(-force[0], rel=1e-8)
    # ContactFields: shear traction and slip as 2-component fields at the slave nodes
    fields = ntf.ContactFields(problem)
    for field, values in ((fields.shear, res.shear), (fields.slip, res.slip)):
        at_nodes = field.x.array.reshape(-1, 2)[res.node]
        np.testing.assert_allclose(at_nodes, values, rtol=0, atol=1e-14 * np.abs(values).max())
    # the springs' own balance: forces on slave and master nodes cancel
    total = problem.states[0].evaluation.forces.sum(axis=(0, 1))
    np.testing.assert_allclose(total, 0.0, atol=1e-12 * force[1])
    assert [len(step) for step in results] == [2, 4]  # fixed increments, all converged


@pytest.mark.serial
def test_stick_stays_below_the_limit():
    """A small drag: every spring sticks, F_T = lambda A t, and F_x < mu F_y."""
    problem, _, ft = _drag(5e-4)
    (res,) = ntf.contact_results(problem)
    assert not res.sliding.any()
    np.testing.assert_allclose(res.shear, STICK_SLOPE * res.slip, rtol=1e-10, atol=0)
    force = ntf.contact_force(problem)
    assert 0.05 * MU * force[1] < -force[0] < MU * force[1]  # really loaded, below the limit
    assert np.all(np.abs(res.shear[:, 0]) < MU * res.pressure)
    top = ntf.reaction(problem, ft.find(UPPER_TOP))
    assert top[0] == pytest.approx(-force[0], rel=1e-8)


@pytest.mark.serial
def test_axisymmetric_sleeve_slides_with_mu_times_the_normal_force():
    """A sleeve pressed onto a fixed tube and pulled along z: F_z = mu F_r to round-off.

    (F_r is not the pressure times the outer area: the sleeve's hoop stress carries a part.)
    """
    problem, _, ft = _drag(0.02, axisymmetric=True, increments=4)
    (res,) = ntf.contact_results(problem)
    assert res.node.size == 4 and res.sliding.all() and np.all(res.normal_force > 0)
    np.testing.assert_allclose(res.normal, np.tile([1.0, 0.0], (4, 1)), atol=1e-14)
    force = ntf.contact_force(problem)  # on the sleeve: the tube pushes it outwards
    assert force[0] > 0.5 * PRESSURE * 2 * np.pi * 1.4 * WIDTH
    assert -force[1] == pytest.approx(MU * force[0], rel=1e-12)
    top = ntf.reaction(problem, ft.find(UPPER_TOP))
    assert top[1] == pytest.approx(-force[1], rel=1e-8)


@pytest.mark.serial
def test_change_friction_between_steps():
    """CHANGE FRICTION: a third step with mu/2 keeps dragging; the new limit holds from then on."""

    def steps_of(problem):
        pair = problem.states[0].pair
        return [
            ntf.AnalysisStep(
                ntf.StaticStep(lambda t: None, initial_increment=0.5, fixed=True),
                changes=[ntf.ChangeFriction(pair, ntf.Friction(MU / 2, STICK_SLOPE))],
                name="half friction",
            )
        ]

    problem, results, _ = _drag(0.02, increments=4, steps_of=steps_of)
    assert len(results) == 3
    (res,) = ntf.contact_results(problem)
    assert res.sliding.all()
    force = ntf.contact_force(problem)
    assert -force[0] == pytest.approx(MU / 2 * force[1], rel=1e-12)
    # the slip history was kept: the accumulated slip did not restart from zero
    assert np.all(res.slip[:, 0] > 0.01)


@pytest.mark.serial
@pytest.mark.parametrize("degree", [1, 2])
def test_global_jacobian_with_friction_matches_finite_differences(degree):
    """The assembled Jacobian of a frictional 2D problem (some springs stick, some slip) is the
    derivative of the residual at a fixed pairing and increment start, by central differences."""
    problem, pressure, drag, _ = drag_problem(degree=degree)
    press_and_drag(problem, pressure, drag, 0.004, increments=4)
    (res,) = ntf.contact_results(problem)
    assert 0 < res.sliding.sum() < res.node.size  # both states in the check
    check = directional_derivative(problem, amplitude=1e-6, h=1e-3, seed=2)
    (after,) = ntf.contact_results(problem)
    np.testing.assert_array_equal(after.sliding, res.sliding)  # no state crossed a kink
    np.testing.assert_allclose(
        check.product, check.difference, rtol=0, atol=1e-7 * check.contact_scale
    )
    assert not check.matrix.isSymmetric(1e-8 * check.matrix.norm())  # friction: unsymmetric


def _frictional_run(comm, partition, degree):
    """Press and drag on ``comm``: (sorted nodes, sorted springs, contact force, increments)."""
    problem, pressure, drag, _ = drag_problem(comm, degree=degree, partition=partition)
    results = press_and_drag(problem, pressure, drag, 0.004, increments=4)
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned, :2]
    nodes = sorted_rows(comm, np.hstack([X, problem.u.x.array.reshape(-1, 2)[:owned]]))
    (table,) = ntf.contact_results(problem)
    springs = sorted_rows(
        comm,
        np.column_stack(
            [table.position, table.pressure, table.shear, table.slip, table.sliding, table.area]
        ),
    )
    increments = [(r.iterations, r.springs) for step in results for r in step]
    force = ntf.contact_force(problem)
    problem.destroy()
    return nodes, springs, force, increments


@functools.lru_cache
def _serial_run(degree):
    return _frictional_run(MPI.COMM_SELF, None, degree)


@pytest.mark.mpi
@pytest.mark.parametrize("degree", [1, 2])
@pytest.mark.parametrize("partition", ["graph", "cut"])
def test_frictional_drag_gives_the_serial_answer(partition, degree):
    """Stick then slip on several processes: every node and spring as in serial."""
    nodes, springs, force, increments = _frictional_run(
        MPI.COMM_WORLD, PARTITIONS[partition], degree
    )
    s_nodes, s_springs, s_force, s_increments = _serial_run(degree)
    assert increments == s_increments
    np.testing.assert_allclose(nodes[:, :2], s_nodes[:, :2], rtol=0, atol=1e-14)
    scale = np.abs(s_nodes[:, 2:]).max()
    np.testing.assert_allclose(nodes[:, 2:], s_nodes[:, 2:], rtol=0, atol=1e-10 * scale)
    assert springs.shape == s_springs.shape and springs.shape[0] == 3 * degree + 1
    assert 0 < s_springs[:, 7].sum() < springs.shape[0]  # some slide, some stick
    np.testing.assert_allclose(springs, s_springs, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(force, s_force, rtol=0, atol=1e-10 * abs(s_force[1]))
