"""PETSc's SNES as the driver of a ContactProblem (solvers/snes.py) against ContactNewtonSolver.

With full Newton steps both drivers make the same iterates: the same iteration counts, pairings
and solution to round-off, serial and in parallel. PETSc's own tests and its backtracking line
search converge to the same solution.
"""

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest
from helpers import drag_problem, punch_problem
from helpers.blocks import (
    LOWER_TOP,
    UPPER_BOTTOM,
    YOUNGS_MODULUS,
    displacement_fields,
    elastic_residual,
    punch_conditions,
    two_blocks,
)
from helpers.serial_answer import sorted_rows

import dolfinx_ntf as ntf

pytestmark = pytest.mark.mpi

NEW_SNES = PETSc.Sys.getVersion() >= (3, 21, 0)


def _press_and_drag(problem, pressure, set_drag):
    def load(t):
        pressure.value = 10.0 * min(1.0, 2 * t)
        set_drag(0.02 * max(0.0, 2 * t - 1))

    return ntf.StaticStep(load, initial_increment=0.25, fixed=True)


def _press(pressure):
    return ntf.StaticStep(
        lambda t: setattr(pressure, "value", 10.0 * t), initial_increment=0.25, fixed=True
    )


def _solve(case, driver, **options):
    """Run ``case`` ("punch", "drag") with ``driver``; returns (iterations, pairings, u of every
    node in the order of their positions)."""
    if case == "drag":
        problem, pressure, set_drag, _ = drag_problem()
        step = _press_and_drag(problem, pressure, set_drag)
    else:
        problem, pressure, _ = punch_problem("hexahedron")
        step = _press(pressure)
    comm = problem.u.function_space.mesh.comm
    if driver == "newton":
        solver = ntf.ContactNewtonSolver(comm, problem, line_search=False, **options)
    else:
        solver = ntf.ContactSNESSolver(comm, problem, **options)
    results = step.run(solver, problem.u)
    # owned nodes sorted by position: two meshes built alike need not be partitioned alike
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned]
    nodes = sorted_rows(comm, np.hstack([X, problem.u.x.array.reshape(-1, 3)[:owned]]))
    return [r.iterations for r in results], problem.pairings, nodes[:, 3:]


@pytest.mark.parametrize("case", ["punch", "drag"])
def test_full_steps_make_the_iterates_of_our_loop(case):
    newton_iterations, newton_pairings, newton_u = _solve(case, "newton")
    snes_iterations, snes_pairings, snes_u = _solve(case, "snes")
    assert snes_iterations == newton_iterations
    assert snes_pairings == newton_pairings
    scale = MPI.COMM_WORLD.allreduce(np.abs(newton_u).max(), op=MPI.MAX)
    assert scale > 1e-3
    assert np.abs(snes_u - newton_u).max() <= 1e-12 * scale


def test_petsc_tolerances_reach_the_same_solution():
    _, _, newton_u = _solve("drag", "newton")
    options = {"snes_rtol": 1e-12, "snes_atol": 1e-13, "snes_stol": 0.0}
    iterations, _, snes_u = _solve("drag", "snes", convergence="petsc", petsc_options=options)
    assert all(n >= 2 for n in iterations)
    scale = MPI.COMM_WORLD.allreduce(np.abs(newton_u).max(), op=MPI.MAX)
    assert np.abs(snes_u - newton_u).max() <= 1e-9 * scale


def test_backtracking_line_search():
    """PETSc >= 3.21 takes the residual norm again after the pairing hook: bt converges to the
    same solution; older PETSc (Debian 12) is refused with the reason."""
    options = {"petsc_options": {"snes_linesearch_type": "bt"}}
    if not NEW_SNES:
        with pytest.raises(ValueError, match=r"'bt' needs PETSc >= 3.21 .* use 'basic'"):
            _solve("drag", "snes", **options)
        return
    _, _, newton_u = _solve("drag", "newton")
    _, _, snes_u = _solve("drag", "snes", **options)
    scale = MPI.COMM_WORLD.allreduce(np.abs(newton_u).max(), op=MPI.MAX)
    assert np.abs(snes_u - newton_u).max() <= 1e-10 * scale


def test_small_sliding_pairs_stay_frozen_within_increments():
    """A small sliding pair is paired at increment starts only, whatever drives the Newton loop;
    PETSc 3.18 accepts any line search then."""
    mesh, _, ft = two_blocks(MPI.COMM_WORLD)
    V, u, v, pressure = displacement_fields(mesh)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)),
        small_sliding=True,
    )
    problem = ntf.ContactProblem(
        elastic_residual(u, v, ft, pressure), u, [pair], punch_conditions(V, ft)
    )
    solver = ntf.ContactSNESSolver(mesh.comm, problem, petsc_options={"snes_linesearch_type": "bt"})
    results = _press(pressure).run(solver, u)
    assert len(results) == 4
    assert problem.pairings == len(results)


def test_failure_raises_contact_convergence_error_with_the_reason():
    problem, pressure, _ = punch_problem("hexahedron")
    solver = ntf.ContactSNESSolver(problem.u.function_space.mesh.comm, problem, max_it=1)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", 10.0 * t), fixed=True)
    with pytest.raises(
        ntf.ContactConvergenceError, match=r"SNES did not converge in 1 .*DIVERGED_MAX_IT"
    ):
        step.run(solver, problem.u)


def test_bad_arguments_are_named():
    problem, _, _ = punch_problem("hexahedron")
    comm = problem.u.function_space.mesh.comm
    with pytest.raises(ValueError, match="convergence must be one of"):
        ntf.ContactSNESSolver(comm, problem, convergence="energy")
    with pytest.raises(ValueError, match="max_it must be an integer >= 1"):
        ntf.ContactSNESSolver(comm, problem, max_it=0)
    with pytest.raises(TypeError, match="problem must be a ContactProblem"):
        ntf.ContactSNESSolver(comm, object())
