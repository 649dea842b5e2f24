"""Newton corrections solved with an earlier factorization: the same iterations and solution as
fresh factorizations, a fresh one when GMRES gives up, and only where it is asked for."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import punch_problem
from helpers.serial_answer import sorted_rows

import dolfinx_ntf as ntf
from dolfinx_ntf.solvers import factor_reuse


def _solve(factorization, max_iterations=None):
    """The punch pressed down in two increments: (iterations per increment, sorted node rows,
    the solver's FactorReuse or None)."""
    problem, pressure, _ = punch_problem("hexahedron")
    comm = problem.u.function_space.mesh.comm
    solver = ntf.ContactNewtonSolver(
        comm, problem, linear_solver="direct", factorization=factorization
    )
    reuse = solver.linear.factor_reuse
    if max_iterations is not None:
        reuse.max_iterations = max_iterations
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", 10.0 * t), initial_increment=0.5)
    results = step.run(solver, problem.u)
    u = problem.u
    owned = u.function_space.dofmap.index_map.size_local
    rows = sorted_rows(
        comm, np.hstack([problem.reference_coordinates[:owned], u.x.array.reshape(-1, 3)[:owned]])
    )
    iterations = [(r.attempt, r.iterations) for r in results]
    solver.destroy()
    problem.destroy()
    return iterations, rows, reuse


@pytest.mark.mpi
def test_reused_factorization_gives_the_fresh_iterations_and_solution():
    """GMRES with the first iteration's factorization solves the later corrections: the Newton
    iterations are those of a fresh factorization per iteration, the solution agrees to 1e-10,
    and fewer factorizations than Newton iterations were made."""
    fresh_iterations, fresh_rows, none = _solve("fresh")
    iterations, rows, reuse = _solve("reuse")
    assert none is None
    assert iterations == fresh_iterations
    assert all(n >= 2 for _, n in iterations)  # corrections after the first: reuse was tried
    assert np.array_equal(rows[:, :3], fresh_rows[:, :3])
    scale = np.abs(fresh_rows[:, 3:]).max()
    assert scale > 0
    assert np.abs(rows[:, 3:] - fresh_rows[:, 3:]).max() <= 1e-10 * scale
    newton = sum(n for _, n in iterations)
    assert reuse.reuses > 0
    assert reuse.factorizations + reuse.reuses == newton
    assert reuse.factorizations < newton


@pytest.mark.mpi
def test_gmres_that_gives_up_factors_afresh():
    """A stale factorization that GMRES cannot use within its limit (here 1 iteration) is
    replaced by a fresh one in the same Newton iteration: the run is the fresh path's."""
    fresh_iterations, fresh_rows, _ = _solve("fresh")
    iterations, rows, reuse = _solve("reuse", max_iterations=1)
    assert iterations == fresh_iterations
    scale = np.abs(fresh_rows[:, 3:]).max()
    assert np.abs(rows[:, 3:] - fresh_rows[:, 3:]).max() <= 1e-10 * scale
    assert reuse.give_ups > 0
    assert reuse.factorizations == sum(n for _, n in iterations) - reuse.reuses


@pytest.mark.mpi
def test_auto_reuses_from_the_size_on():
    """``"auto"`` reuses from ``REUSE_MIN_DOFS`` dofs on; a bad value names the argument."""
    assert not factor_reuse.reuses_factorization("auto", factor_reuse.REUSE_MIN_DOFS - 1)
    assert factor_reuse.reuses_factorization("auto", factor_reuse.REUSE_MIN_DOFS)
    assert factor_reuse.reuses_factorization("reuse", 10)
    assert not factor_reuse.reuses_factorization("fresh", 10**9)
    problem, _, _ = punch_problem("hexahedron")
    comm = problem.u.function_space.mesh.comm
    with ntf.ContactNewtonSolver(comm, problem) as solver:  # a small problem: fresh
        assert solver.linear.factor_reuse is None
    with pytest.raises(ValueError, match="ContactNewtonSolver: factorization must be one of"):
        ntf.ContactNewtonSolver(comm, problem, factorization="stale")
    problem.destroy()


@pytest.mark.mpi
def test_iterative_solver_is_left_alone():
    """With GMRES + GAMG the reuse has nothing to reuse: the Krylov solver solves as configured."""
    problem, pressure, _ = punch_problem("hexahedron")
    comm = problem.u.function_space.mesh.comm
    with ntf.ContactNewtonSolver(
        comm, problem, linear_solver="iterative", factorization="reuse"
    ) as solver:
        step = ntf.StaticStep(lambda t: setattr(pressure, "value", 10.0 * t))
        step.run(solver, problem.u)
        assert solver.krylov_solver.getPC().getType() == "gamg"
        assert solver.linear.factor_reuse.factorizations == 0
        assert solver.linear.factor_reuse.reuses == 0
    problem.destroy()


@pytest.mark.serial
def test_deck_runner_reuse_matches_fresh(tmp_path):
    """``run_job(factorization=...)``: the deck's iterations and printed values agree."""
    from pathlib import Path

    from dolfinx_ntf.calculix.dat import read_dat
    from dolfinx_ntf.calculix.job import run_job

    deck = Path(__file__).parents[1] / "data" / "calculix" / "two_cubes.inp"
    results = {}
    for path in ("fresh", "reuse"):
        directory = tmp_path / path
        directory.mkdir()
        (directory / deck.name).write_bytes(deck.read_bytes())
        result = run_job("two_cubes", directory, comm=MPI.COMM_SELF, progress=False,
                         factorization=path)  # fmt: skip
        results[path] = [i.iterations for i in result.increments], read_dat(result.dat)
    assert results["reuse"][0] == results["fresh"][0]
    for fresh, reuse in zip(results["fresh"][1], results["reuse"][1]):
        scale = max(np.abs(fresh.values).max(initial=0.0), 1e-300)
        assert np.abs(reuse.values - fresh.values).max(initial=0.0) <= 1e-8 * scale
    with pytest.raises(ValueError, match="factorization 'stale'"):
        run_job("two_cubes", tmp_path / "fresh", comm=MPI.COMM_SELF, factorization="stale")


@pytest.mark.serial
def test_command_line_factorization_option(tmp_path, capsys):
    """``--factorization reuse`` runs the deck; an unknown value is a usage error (exit 1)."""
    from pathlib import Path

    from dolfinx_ntf.__main__ import main
    from dolfinx_ntf.calculix.dat import read_dat

    deck = Path(__file__).parents[1] / "data" / "calculix" / "two_cubes.inp"
    (tmp_path / deck.name).write_bytes(deck.read_bytes())
    assert main(["run", "--factorization", "reuse", str(tmp_path / "two_cubes")]) == 0
    assert read_dat(tmp_path / "two_cubes.dat")
    assert main(["run", "--factorization", "stale", str(tmp_path / "two_cubes")]) == 1
    assert "--factorization" in capsys.readouterr().err
