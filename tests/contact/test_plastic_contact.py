"""J2 plasticity with frictional contact (fem/plasticity.py through ContactProblem's history).

A punch (the upper block, slave) pressed onto a block (master) by a pressure on its top, both of a
metal with a ``*PLASTIC`` table, Coulomb friction between them: the punch yields, the converged
contact force is the applied load, Newton converges quadratically in the plastic increments, the
unloading is elastic (the committed plastic strains stay), a cut-back attempt leaves the history
alone, and 2 processes give the serial answer node by node.
"""

from __future__ import annotations

import itertools

from mpi4py import MPI

import numpy as np
import pytest
from helpers import (
    LOWER_TOP,
    PUNCH,
    UPPER_BOTTOM,
    UPPER_TOP,
    displacement_fields,
    punch_conditions,
    two_blocks,
)
from helpers.serial_answer import empty_last, sorted_rows

import ufl

import dolfinx_ntf as ntf

E, NU = 1000.0, 0.3
HARDENING = ntf.IsotropicHardening((1.0, 1.2, 1.3), (0.0, 0.01, 0.05))
PEAK, RESIDUAL_LOAD = 1.6, 0.2  # top pressures: past yield (sigma_y0 = 1), then unloaded
TOP_AREA = PUNCH[1][0] * PUNCH[1][1]


def _plastic_punch(comm=MPI.COMM_WORLD, partition=None, **solver_options):
    """The problem, its solver, the material and the pressure Constant (0)."""
    mesh, _, ft = two_blocks(comm, upper=PUNCH, partition=partition)
    V, u, v, pressure = displacement_fields(mesh)
    material = ntf.J2Plasticity(u, E, NU, HARDENING)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    F = material.residual(v) + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(UPPER_TOP)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E), ntf.Friction(0.3, 50 * E)),
        name="punch",
    )
    problem = ntf.ContactProblem(
        F,
        u,
        [pair],
        punch_conditions(V, ft),
        J=material.jacobian(ufl.TrialFunction(V), v),
        history=[material],
    )
    solver = ntf.ContactNewtonSolver(mesh.comm, problem, **solver_options)
    return problem, solver, material, pressure


def _largest(comm, values: np.ndarray) -> float:
    return comm.allreduce(float(np.max(values, initial=0.0)), op=MPI.MAX)


def _load_and_unload(comm, partition=None):
    """Press to PEAK in increments of 0.25, unload to RESIDUAL_LOAD in two; per increment:
    (pressure, contact force, largest alpha, yielding points, residual norms, iterations)."""
    problem, solver, material, pressure = _plastic_punch(comm, partition)
    records = []

    def record(result: ntf.IncrementResult) -> None:
        records.append(
            (
                float(pressure.value),
                ntf.contact_force(problem, "punch"),
                _largest(comm, material.equivalent_plastic_strain),
                comm.allreduce(int(material.yielding.sum())),
                list(solver.residual_norms),
                result.iterations,
            )
        )

    ntf.StaticStep(
        lambda t: setattr(pressure, "value", PEAK * t), initial_increment=0.25, on_increment=record
    ).run(solver, problem.u)
    loaded = material.equivalent_plastic_strain.copy()
    ntf.StaticStep(
        lambda t: setattr(pressure, "value", PEAK - (PEAK - RESIDUAL_LOAD) * t),
        initial_increment=0.5,
        on_increment=record,
    ).run(solver, problem.u)
    return problem, solver, material, records, loaded


@pytest.mark.mpi
def test_force_balance_yield_and_elastic_unloading() -> None:
    """The contact force equals the load at every converged increment (loading and unloading);
    the punch yields; unloading yields nowhere and keeps the committed plastic strains."""
    comm = MPI.COMM_WORLD
    problem, solver, material, records, loaded = _load_and_unload(comm)
    for load, force, *_ in records:
        np.testing.assert_allclose(force, [0.0, 0.0, load * TOP_AREA], rtol=1e-9, atol=1e-11)
    peak = next(r for r in records if r[0] == pytest.approx(PEAK))
    assert peak[2] > 1e-3 and peak[3] > 0  # plastic flow at the peak
    unloading = records[-2:]
    assert [r[0] for r in unloading] == pytest.approx([0.9, RESIDUAL_LOAD])
    assert all(r[3] == 0 for r in unloading)  # elastic unloading
    np.testing.assert_array_equal(material.equivalent_plastic_strain, loaded)
    assert _largest(comm, material.equivalent_plastic_strain) == peak[2]
    solver.destroy()
    problem.destroy()


def test_quadratic_convergence_in_plastic_increments() -> None:
    """Newton with the consistent tangent: in every plastic increment the residual's exponent
    (relative to the first) at least doubles, less 10 %, between the last iterates above
    round-off, and the increment converges in a few iterations."""
    comm = MPI.COMM_WORLD
    problem, solver, _, records, _ = _load_and_unload(comm)
    plastic = [r for r in records if r[3] > 0]
    assert len(plastic) >= 2
    for *_, norms, iterations in plastic:
        assert iterations <= 8
        relative = np.array(norms[1:]) / norms[0]
        rates = [
            np.log(b) / np.log(a) for a, b in itertools.pairwise(relative) if a < 1e-2 and b > 1e-13
        ]
        assert rates and max(rates) > 1.8, (norms, rates)
    solver.destroy()
    problem.destroy()


def test_cutback_rolls_the_history_back() -> None:
    """A failed attempt (injected in the third evaluation of the first increment, when the punch
    has yielded in the trial) is cut back; its trial history is dropped (reject_increment) and the
    analysis ends on the answer of the same increments run without failure."""
    comm = MPI.COMM_WORLD
    calls = []

    class Spy:
        """A second history that fails one attempt and records what the step driver calls."""

        evaluations = 0

        def evaluate(self) -> None:
            Spy.evaluations += 1
            if Spy.evaluations == 3:
                calls.append("failed")
                raise ntf.ContactConvergenceError("injected failure")

        def increment_converged(self) -> None:
            calls.append("converged")

        def increment_rejected(self) -> None:
            calls.append("rejected")

    problem, solver, material, pressure = _plastic_punch(comm)
    problem.history.append(Spy())
    results = ntf.StaticStep(
        lambda t: setattr(pressure, "value", PEAK * t), initial_increment=1.0
    ).run(solver, problem.u)
    assert calls[:3] == ["failed", "rejected", "converged"]
    assert calls.count("converged") == len(results) >= 2 and results[0].attempt == 2
    times = [r.time for r in results]
    alpha = material.equivalent_plastic_strain.copy()
    assert _largest(comm, alpha) > 1e-3
    u = problem.u.x.array.copy()
    solver.destroy()
    problem.destroy()
    # the same increments without failures: the same committed state
    problem, solver, material, pressure = _plastic_punch(comm)
    for t in times:
        ntf.StaticStep(lambda s, t=t: setattr(pressure, "value", PEAK * t)).run(solver, problem.u)
    np.testing.assert_allclose(material.equivalent_plastic_strain, alpha, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(problem.u.x.array, u, rtol=1e-8, atol=1e-12)
    solver.destroy()
    problem.destroy()


def _answer(comm, partition=None):
    """Sorted rows (reference position, displacement) of the owned nodes after the analysis, and
    the largest committed alpha."""
    problem, solver, material, _, _ = _load_and_unload(comm, partition)
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned]
    rows = sorted_rows(comm, np.hstack([X, problem.u.x.array.reshape(-1, 3)[:owned]]))
    alpha = _largest(comm, material.equivalent_plastic_strain)
    solver.destroy()
    problem.destroy()
    return rows, alpha


@pytest.mark.mpi
@pytest.mark.parametrize("partition", [None, empty_last], ids=["dolfinx", "empty-last"])
def test_parallel_run_is_the_serial_one(partition) -> None:
    """On every process count the displacements node by node and the largest plastic strain are
    the serial run's (each process also runs the serial problem on COMM_SELF); also with a last
    process that holds no cell (and no quadrature point)."""
    rows, alpha = _answer(MPI.COMM_WORLD, partition)
    serial_rows, serial_alpha = _answer(MPI.COMM_SELF)
    np.testing.assert_allclose(rows[:, :3], serial_rows[:, :3], atol=1e-12)
    scale = np.abs(serial_rows[:, 3:]).max()
    np.testing.assert_allclose(rows[:, 3:], serial_rows[:, 3:], rtol=0, atol=1e-8 * scale)
    assert alpha == pytest.approx(serial_alpha, rel=1e-8)


def test_elastic_start_needs_an_elastic_evaluation() -> None:
    """``begin_increment(elastic_start=True)`` (ccx's elastic first iteration, docs/method.md
    §33) names a history entry without ``evaluate_elastic``; without prescribed displacements
    (this punch is pressure-loaded) the first iterate return-maps as usual."""
    comm = MPI.COMM_WORLD

    class Plain:
        def evaluate(self) -> None:
            pass

        def increment_converged(self) -> None:
            pass

        def increment_rejected(self) -> None:
            pass

    problem, solver, material, pressure = _plastic_punch(comm)
    problem.history.append(Plain())
    with pytest.raises(
        TypeError, match=r"elastic_start needs history entries with evaluate_elastic\(\)"
    ):
        problem.begin_increment(1.0, elastic_start=True)
    problem.history.pop()
    elastic_calls = []
    original = material.evaluate_elastic
    material.evaluate_elastic = lambda: elastic_calls.append(1) or original()
    ntf.StaticStep(
        lambda t: setattr(pressure, "value", PEAK * t), initial_increment=1.0, elastic_start=True
    ).run(solver, problem.u)
    assert not elastic_calls  # no prescribed displacement changes: ccx's rule does not apply
    solver.destroy()
    problem.destroy()


@pytest.mark.parametrize("contact", ["start", "stick"])
def test_elastic_contact_is_asked_for_in_the_first_increment_only(contact: str) -> None:
    """``StaticStep(elastic_contact=...)`` (docs/method.md §33.4) asks the problem in the step's
    first increment only; it acts only where prescribed displacements change, so this
    pressure-loaded punch is evaluated as usual (the springs at the iterate, no forced stick);
    an unknown value is a ``ValueError``."""
    problem, solver, _, pressure = _plastic_punch(MPI.COMM_WORLD)
    asked, forced = [], []
    begin, evaluate = problem.begin_increment, problem.evaluate

    def spy_begin(fraction: float, **options) -> None:
        asked.append(options.get("elastic_contact", "iterate"))
        begin(fraction, **options)

    def spy_evaluate(**options):
        forced.append(options.get("force_stick", False))
        return evaluate(**options)

    problem.begin_increment, problem.evaluate = spy_begin, spy_evaluate
    results = ntf.StaticStep(
        lambda t: setattr(pressure, "value", PEAK * t),
        initial_increment=0.5,
        max_increment=0.5,
        elastic_contact=contact,
    ).run(solver, problem.u)
    assert len(results) == 2 and asked == [contact, "iterate"]
    assert forced and not any(forced)
    with pytest.raises(ValueError, match="elastic_contact must be one of"):
        begin(1.0, elastic_contact="ccx")
    solver.destroy()
    problem.destroy()
