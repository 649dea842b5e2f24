"""The package as a FEniCSx user meets it: version, exports, user-defined laws, a step that holds
configuration only, PETSc options and objects cleaned up, progress lines and quiet libraries."""

import gc
import importlib.metadata
import logging

from petsc4py import PETSc

import numpy as np
import pytest
from helpers import punch_problem, two_blocks

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat, logs

pytestmark = pytest.mark.serial

E, LOAD = 1000.0, 10.0


def _problem(law=None):
    problem, pressure, _ = punch_problem(law=law)
    return problem, pressure


def test_version_matches_the_installed_metadata():
    assert ntf.__version__ == importlib.metadata.version("dolfinx_ntf")


def test_user_defined_law():
    """A law of one's own: subclass PressureOverclosureLaw (exported) and use it like ccx's."""

    class Quadratic(ntf.PressureOverclosureLaw):
        """p = k d |d| + s d: a smooth stiffening penalty."""

        keyword = "USER"

        def __init__(self, k, s):
            self.k, self.s = k, s

        def pressure(self, d):
            d = self._d(d)
            return self.k * d * np.abs(d) + self.s * d

        def pressure_derivative(self, d):
            return 2 * self.k * np.abs(self._d(d)) + self.s

        def cutoff(self, area):
            return 1e-3 * np.sqrt(np.asarray(area, dtype=float))

        def energy(self, d, area):
            d, area = self._d_area(d, area)
            return area * (self.k * np.abs(d) ** 3 / 3 + self.s * d**2 / 2)

    problem, pressure = _problem(Quadratic(1e8, 5e4))
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
    assert ntf.contact_force(problem)[2] == pytest.approx(LOAD * 0.36, rel=1e-10)


def test_step_holds_configuration_only():
    step = ntf.StaticStep(lambda t: None, initial_increment=0.5)
    assert not hasattr(step, "results")
    runs = []
    for _ in range(2):  # the same step on two fresh problems: each run returns its own results
        problem, pressure = _problem()
        step.set_load = lambda t, p=pressure: setattr(p, "value", LOAD * t)
        solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
        runs.append(step.run(solver, problem.u))
    assert [len(r) for r in runs] == [2, 2]
    assert [r.time for r in runs[1]] == [0.5, 1.0]


def test_petsc_options_are_read_once_and_removed():
    problem, _ = _problem()
    before = set(PETSc.Options().getAll())
    solver = ntf.ContactNewtonSolver(
        problem.u.function_space.mesh.comm,
        problem,
        petsc_options={
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "superlu_dist",
        },
        options_prefix="test_removed_",
    )
    assert set(PETSc.Options().getAll()) == before
    pc = solver.krylov_solver.getPC()
    assert (solver.krylov_solver.getType(), pc.getType(), pc.getFactorSolverType()) == (
        "preonly",
        "lu",
        "superlu_dist",
    )
    solver.destroy()
    problem.destroy()


def test_owned_petsc_objects_are_destroyed():
    problem, pressure = _problem()
    with problem, ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem) as solver:
        ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
        matrix, vector = problem.matrix, solver.b
    assert problem.matrix is None
    assert matrix.handle == 0 and vector.handle == 0  # PETSc objects freed


def test_the_jacobian_belongs_to_the_problem():
    """A solver that goes away frees its residual vector, not the problem's Jacobian."""
    problem, pressure = _problem()
    comm = problem.u.function_space.mesh.comm
    solver = ntf.ContactNewtonSolver(comm, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", 0.5 * LOAD * t)).run(solver, problem.u)
    matrix = problem.matrix
    del solver
    gc.collect()
    assert problem.matrix is matrix and matrix.handle != 0
    solver = ntf.ContactNewtonSolver(comm, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
    assert ntf.contact_force(problem)[2] == pytest.approx(LOAD * 0.36, rel=1e-10)


def test_one_progress_line_per_increment_by_default(progress_lines):
    """A Python user sees one line per increment; CalculiX's per-attempt and per-pairing lines
    only with details=True (the deck runner's choice)."""
    ntf.log_progress()
    problem, pressure = _problem()
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    assert len(results) == 2
    increments = [line for line in progress_lines if " converged: time " in line]
    assert [line.split(" converged")[0] for line in increments] == [" increment 1", " increment 2"]
    assert all("iterations" in line and "contact elements" in line for line in increments)
    assert not [line for line in progress_lines if "Number of contact spring elements" in line]
    assert not [line for line in progress_lines if "increment size=" in line]
    progress_lines.clear()
    ntf.log_progress(details=True)
    problem, pressure = _problem()
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    step.run(solver, problem.u)
    assert [line for line in progress_lines if "Number of contact spring elements" in line]
    assert len([line for line in progress_lines if "increment size=" in line]) == 2


def test_one_progress_line_per_newton_iteration(progress_lines):
    problem, pressure = _problem()
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    ntf.log_progress()
    ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
    assert not [line for line in progress_lines if line.startswith(" iteration")]
    progress_lines.clear()
    ntf.log_progress(iterations=True)
    problem, pressure = _problem()
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    results = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t)).run(solver, problem.u)
    lines = [line for line in progress_lines if line.startswith(" iteration")]
    assert len(lines) == results[0].iterations + 1  # the initial residual, then one per update
    assert lines[0].startswith(" iteration 0: residual ")
    assert " contact elements" in lines[0]
    assert "correction" in lines[1] and "of the first" in lines[1]
    assert lines[-1].endswith(", converged")


def test_dolfinx_newton_warning_is_silenced(capfd):
    problem, pressure = _problem()
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem, max_it=1)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), fixed=True)
    with pytest.raises(ntf.ContactConvergenceError, match="did not converge in 1 iterations"):
        step.run(solver, problem.u)
    assert "Newton solver did not converge" not in capfd.readouterr().err


def test_jit_compiler_lines_go_to_the_library_logger(tmp_path, capfd):
    records = []

    class Keep(logging.Handler):
        def emit(self, record):
            records.append(record.getMessage())

    handler = Keep(logging.DEBUG)
    saved = logs.jit_logger.level
    logs.jit_logger.addHandler(handler)
    logs.jit_logger.setLevel(logging.DEBUG)
    try:
        mesh = two_blocks()[0]
        V = compat.vector_space(mesh, "Lagrange", 1)
        f = dolfinx.fem.Function(V)
        form = ufl.inner(f, ufl.TestFunction(V)) * 3.25 * ufl.dx
        dolfinx.fem.form(form, **compat.jit_keywords(None, {"cache_dir": str(tmp_path)}))
    finally:
        logs.jit_logger.removeHandler(handler)
        logs.jit_logger.setLevel(saved)
    assert "INFO:root" not in capfd.readouterr().err
    assert any("gcc" in r or "build_ext" in r for r in records)
