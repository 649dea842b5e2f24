"""Newton iterations of the two drivers, ContactNewtonSolver and ContactSNESSolver, on the demos.

Every demo of ``demos/`` runs three times (coarse meshes unless ``--full``; the Hertz sphere also
on its default ~26k-dof mesh of the pinned quarter sphere with ``--sphere``):

- ``newton``: as written, :class:`~dolfinx_ntf.ContactNewtonSolver` with its defaults (line
  search from the second update);
- ``snes basic``: :class:`~dolfinx_ntf.ContactSNESSolver` with full Newton steps;
- ``snes bt``: PETSc's backtracking line search (PETSc >= 3.21 only: older SNES keep the residual
  norm from before a re-pairing, see ``solvers/snes.py``).

The demos build ``ntf.ContactNewtonSolver(comm, problem, ...)``; this script replaces that name
for the SNES runs by a factory that builds a ContactSNESSolver from the same problem (the
``controls`` carried over, other Newton options dropped). It prints increments, total and largest
Newton iterations per increment, wall time, and the largest difference of the final displacement
from the ``newton`` run over its largest displacement.

    .venv/bin/python benchmarks/snes_vs_newton.py              # coarse demos (about 1 minute)
    .venv/bin/python benchmarks/snes_vs_newton.py --sphere     # and the 26k-dof Hertz sphere
    .venv/bin/python benchmarks/snes_vs_newton.py --only --sphere   # the 26k-dof Hertz sphere alone
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import io
import tempfile
import time
import typing
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx_ntf as ntf

DEMOS = Path(__file__).resolve().parents[1] / "demos"
NAMES = ("punch", "frictional_punch", "sliding_block", "hertz_sphere", "impact")


class _Recorder:
    """Builds the solver of a run and remembers it (iterations per solve, final displacement)."""

    def __init__(self, driver: str) -> None:
        self.driver = driver
        self.iterations: list[int] = []
        self.solvers: list[typing.Any] = []

    def __call__(self, comm: MPI.Comm, problem: ntf.ContactProblem, **options: typing.Any):
        if self.driver == "newton":
            solver = _NEWTON(comm, problem, **options)
        else:
            petsc = {"snes_linesearch_type": "bt"} if self.driver == "snes bt" else None
            keep = {k: v for k, v in options.items() if k == "controls"}
            solver = ntf.ContactSNESSolver(comm, problem, petsc_options=petsc, **keep)
        solve = solver.solve

        def counted(u):
            iterations, converged = solve(u)
            self.iterations.append(iterations)
            return iterations, converged

        solver.solve = counted
        self.solvers.append(solver)
        return solver

    def displacement(self) -> np.ndarray:
        return self.solvers[-1].problem.u.x.array.copy()


_NEWTON = ntf.ContactNewtonSolver


@contextlib.contextmanager
def _driver(recorder: _Recorder) -> typing.Iterator[None]:
    ntf.ContactNewtonSolver = recorder
    try:
        yield
    finally:
        ntf.ContactNewtonSolver = _NEWTON


def _run(name: str, driver: str, argv: list[str]) -> tuple[_Recorder, float]:
    spec = importlib.util.spec_from_file_location(f"_demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    recorder = _Recorder(driver)
    quiet = contextlib.redirect_stdout(io.StringIO())
    with tempfile.TemporaryDirectory() as output, _driver(recorder), quiet:
        start = time.perf_counter()
        module.main([*argv, "--quiet", "--output", output])
        return recorder, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--full", action="store_true", help="the demos' default meshes")
    parser.add_argument("--sphere", action="store_true", help="add the 26k-dof Hertz sphere")
    parser.add_argument("--only", nargs="*", default=None, help="demo names")
    args = parser.parse_args()
    drivers = ["newton", "snes basic"]
    if PETSc.Sys.getVersion() >= (3, 21, 0):
        drivers.append("snes bt")
    names = NAMES if args.only is None else args.only
    runs = [(n, [] if args.full else ["--coarse"]) for n in names]
    if args.sphere:
        runs.append(("hertz_sphere", []))
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        version = ".".join(map(str, PETSc.Sys.getVersion()))
        print(f"PETSc {version}, {comm.size} process(es)")
        print(
            f"{'demo':<28} {'driver':<11} {'incr.':>5} {'iter.':>5} {'max/incr.':>9} "
            f"{'time s':>7} {'|du|/|u|':>9}"
        )
    for name, argv in runs:
        label = name + ("" if argv else " (default mesh)")
        reference = None
        for driver in drivers:
            try:
                recorder, seconds = _run(name, driver, argv)
            except ntf.ContactConvergenceError as error:
                if comm.rank == 0:
                    print(f"{label:<28} {driver:<11} failed: {error}")
                continue
            u = recorder.displacement()
            if reference is None:
                reference = u
            scale = comm.allreduce(np.abs(reference).max(), op=MPI.MAX)
            difference = comm.allreduce(np.abs(u - reference).max(), op=MPI.MAX) / scale
            its = recorder.iterations
            if comm.rank == 0:
                print(
                    f"{label:<28} {driver:<11} {len(its):>5} {sum(its):>5} {max(its):>9} "
                    f"{seconds:>7.1f} {difference:>9.1e}"
                )


if __name__ == "__main__":
    main()
