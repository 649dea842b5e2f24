"""Friction on a small mesh: a punch pressed onto a block, then dragged (stick, then slip)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_BOTTOM, MU, PRESSURE, STICK_SLOPE, UPPER_TOP, drag_problem

import dolfinx_ntf as ntf

pytestmark = pytest.mark.serial


def _press_and_drag(drag_to, *, increments=2, **options):
    problem, pressure, set_drag, ft = drag_problem(**options)
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)

    def press(t):
        pressure.value = PRESSURE * t

    ntf.StaticStep(press, initial_increment=0.5, fixed=True).run(solver, problem.u)
    ntf.StaticStep(
        lambda t: set_drag(drag_to * t), initial_increment=1 / increments, fixed=True
    ).run(solver, problem.u)
    return problem, solver, ft


def test_stick_then_slip_on_a_mesh():
    # stick: a small drag; tau = lambda (t - t_p) with t_p = 0 at every spring
    problem, _, ft = _press_and_drag(2e-4)
    (res,) = ntf.contact_results(problem)
    assert res.node.size == 16 and not res.sliding.any()
    np.testing.assert_allclose(res.shear, STICK_SLOPE * res.slip, rtol=1e-10, atol=0)
    assert np.all(np.linalg.norm(res.shear, axis=1) < MU * res.pressure)
    assert np.abs(res.shear[:, 0]).max() > 0.01  # really loaded
    # the punch is in equilibrium: the support of its top takes what the contact transmits
    top = ntf.reaction(problem, ft.find(UPPER_TOP))
    bottom = ntf.reaction(problem, ft.find(LOWER_BOTTOM))
    force = ntf.contact_force(problem)
    np.testing.assert_allclose(top[:2] + force[:2], 0, atol=1e-8 * abs(force[0]))
    np.testing.assert_allclose(top[:2] + bottom[:2], 0, atol=1e-8 * abs(force[0]))

    # slip: a large drag; |tau| = mu p at every spring
    problem, _, ft = _press_and_drag(0.1, increments=4)
    (res,) = ntf.contact_results(problem)
    assert res.sliding.all()
    np.testing.assert_allclose(
        np.linalg.norm(res.shear, axis=1), MU * res.pressure, rtol=1e-10, atol=0
    )
    force = ntf.contact_force(problem)
    # the master resists the drag with about mu times the load (the rest: tilted normals)
    assert -force[0] == pytest.approx(MU * force[2], rel=0.1)
    top = ntf.reaction(problem, ft.find(UPPER_TOP))
    np.testing.assert_allclose(top[:2] + force[:2], 0, atol=1e-8 * abs(force[0]))
    # every spring is self-equilibrated: contact forces on both sides cancel
    total = sum(s.evaluation.forces.sum(axis=(0, 1)) for s in problem.states)
    np.testing.assert_allclose(total, 0, atol=1e-10 * abs(force[2]))


def test_writer_has_the_friction_fields(tmp_path):
    problem, _, _ = _press_and_drag(2e-3)
    with ntf.ContactWriter(problem, tmp_path / "drag.xdmf") as writer:
        writer.write(1.0)
        shear = writer.fields.shear.x.array.reshape(-1, 3)
    (res,) = ntf.contact_results(problem)
    np.testing.assert_allclose(shear[res.node], res.shear)
    text = (tmp_path / "drag.xdmf").read_text()
    assert "contact_shear" in text and "contact_slip" in text


def test_friction_jacobian_is_unsymmetric_and_lu():
    problem, solver, _ = _press_and_drag(2e-3, symmetric=True)
    assert problem.has_friction
    assert solver.krylov_solver.getPC().getType() == "lu"
    A = problem.matrix
    assert not A.isSymmetric(1e-8 * A.norm())


def test_cutback_restores_the_friction_state():
    """A failed attempt that moved the nodes leaves no trace in the friction state."""
    reference, *_ = _press_and_drag(2e-2, increments=4)
    problem, pressure, set_drag, _ = drag_problem()
    solver = ntf.ContactNewtonSolver(MPI.COMM_WORLD, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", PRESSURE * t), initial_increment=0.5,
                   fixed=True).run(solver, problem.u)  # fmt: skip
    solve = solver.solve
    failed = []

    def failing_solve(u):
        if not failed:  # mess the state up, then fail
            failed.append(True)
            u.x.array[:] += 1e-3
            problem.evaluate(tangent=False)
            raise ntf.ContactConvergenceError("forced failure")
        return solve(u)

    solver.solve = failing_solve
    results = ntf.StaticStep(
        lambda t: set_drag(2e-2 * t), initial_increment=0.5, min_increment=0.01, growth_factor=1.0
    ).run(solver, problem.u)
    assert failed and results[0].attempt == 2 and len(results) == 4
    (a,), (b,) = ntf.contact_results(reference), ntf.contact_results(problem)
    assert a.sliding.any() and not a.sliding.all()  # a mixed stick/slip state
    np.testing.assert_allclose(b.shear, a.shear, atol=1e-9 * np.abs(a.shear).max())
    np.testing.assert_allclose(b.slip, a.slip, atol=1e-9 * np.abs(a.slip).max())
