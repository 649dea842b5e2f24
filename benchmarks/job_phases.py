"""Where the time of one deck run goes: ``run_job``'s phases, CPU and wall, median over runs.

Each run is a process of its own (``--driver``): it imports what ``python -m dolfinx_ntf run``
imports, then calls :func:`dolfinx_ntf.calculix.job.run_job` with timers around its phases:

- ``imports``: ``import dolfinx`` (the floor) and then dolfinx_ntf's deck runner;
- ``deck``, ``model``: ``read_deck``, ``build_model``;
- ``set-up``: the job's files, problem, Newton solver and XDMF writer (``_Job``);
- per Newton iteration: ``jacobian`` (bulk and springs into the matrix), ``linear solve``
  (``LinearSolver.solve`` and the Krylov solver's ``solve``: MUMPS's analysis, once, its numeric
  factorizations, the triangular solves and, where an earlier factorization is reused
  (``solvers/factor_reuse.py``), GMRES), ``residual`` (forms, springs, residual, convergence
  test), ``pairing``;
- ``matrix``: the matrix with its contact pattern (``ContactProblem.ensure_matrix``);
- outputs: ``.dat``/``.frd`` (``JobFiles.write_increment``), ``.cel`` (each pairing's contact
  elements), ``.xdmf`` (``ContactWriter.write``); ``other``: what ``run_job`` spent elsewhere.

Each phase's time is its own: a phase timed inside another (a pairing inside the Jacobian's
evaluation, the ``.cel`` lines inside a pairing) counts in the inner one only.

Serial, one thread (``OMP_NUM_THREADS`` and ``OPENBLAS_NUM_THREADS`` = 1), the checkout
byte-compiled first (``startup.compile_bytecode``). The machine's 1-minute load average is printed
with the table: on a shared machine the CPU times are what to compare. One more, untimed run asks
MUMPS for its statistics (``-ntf_mat_mumps_icntl_4 2``, under the Newton solver's prefix): the
ordering it used, the entries of the factors and the operations of one factorization, which set
the linear solve's time.

    .venv/bin/python benchmarks/job_phases.py                  # punch_20, 5 runs
    .venv/bin/python benchmarks/job_phases.py DECK.inp --runs 3
    .venv/bin/python benchmarks/job_phases.py --write          # its section of docs/performance.md
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from driver_run import run_driver

ROOT = Path(__file__).resolve().parents[1]

#: Phases in table order: (name, what the driver times).
PHASES = (
    "import dolfinx",
    "imports",
    "deck",
    "model",
    "set-up",
    "matrix",
    "jacobian",
    "linear solve",
    "residual",
    "pairing",
    ".dat/.frd",
    ".cel",
    ".xdmf",
    "other",
)


def _driver(job: str) -> None:
    """In the child: run ``job`` with timers; print the phases' (CPU, wall) as JSON."""
    clock: dict[str, list[float]] = {}
    start = (time.process_time(), time.perf_counter())
    import dolfinx  # noqa: F401

    floor = (time.process_time(), time.perf_counter())
    import gc
    import logging

    logging.getLogger().setLevel(logging.WARNING)
    from dolfinx_ntf.calculix import job as job_module
    from dolfinx_ntf.calculix import job_files
    from dolfinx_ntf.contact import problem
    from dolfinx_ntf.outputs import results
    from dolfinx_ntf.solvers import factor_reuse, linear_solver, newton, newton_loop

    gc.freeze()  # as python -m dolfinx_ntf run does
    imported = (time.process_time(), time.perf_counter())
    clock["import dolfinx"] = [floor[0] - start[0], floor[1] - start[1]]
    clock["imports"] = [imported[0] - floor[0], imported[1] - floor[1]]
    stack: list[list[float]] = []  # per open phase: CPU and wall of the phases inside it

    def timed(name: str, function: Callable) -> Callable:
        """``function`` timed as phase ``name``, without the phases timed inside it."""

        def wrapper(*args, **kwargs):
            stack.append([0.0, 0.0])
            cpu, wall = time.process_time(), time.perf_counter()
            try:
                return function(*args, **kwargs)
            finally:
                spent = (time.process_time() - cpu, time.perf_counter() - wall)
                inner = stack.pop()
                entry = clock.setdefault(name, [0.0, 0.0])
                for k in (0, 1):
                    entry[k] += spent[k] - inner[k]
                    if stack:
                        stack[-1][k] += spent[k]

        return wrapper

    job_module.read_deck = timed("deck", job_module.read_deck)
    job_module.build_model = timed("model", job_module.build_model)
    job_module._Job.__init__ = timed("set-up", job_module._Job.__init__)
    job_module._Job._on_pairing = timed(".cel", job_module._Job._on_pairing)
    problem.ContactProblem.ensure_matrix = timed("matrix", problem.ContactProblem.ensure_matrix)
    problem.ContactProblem.J = timed("jacobian", problem.ContactProblem.J)
    problem.ContactProblem.pair = timed("pairing", problem.ContactProblem.pair)
    for name in ("_residual", "_form", "is_converged"):
        method = getattr(newton.ContactNewtonSolver, name)
        setattr(newton.ContactNewtonSolver, name, timed("residual", method))
    job_files.JobFiles.write_increment = timed(".dat/.frd", job_files.JobFiles.write_increment)
    results.ContactWriter.write = timed(".xdmf", results.ContactWriter.write)
    linear_solver.LinearSolver.solve = timed("linear solve", linear_solver.LinearSolver.solve)

    class _TimedKrylov:
        """The Newton loop's Krylov solver with its ``solve`` timed."""

        def __init__(self, ksp: object) -> None:
            self._ksp = ksp
            self.solve = timed("linear solve", ksp.solve)

        def __getattr__(self, name: str) -> object:
            return getattr(self._ksp, name)

    iterate = newton_loop.NewtonSolver._iterate

    def timed_iterate(self, x):
        if not isinstance(self.krylov_solver, _TimedKrylov):
            self.krylov_solver = _TimedKrylov(self.krylov_solver)
        return iterate(self, x)

    newton_loop.NewtonSolver._iterate = timed_iterate
    counts = {"factorizations": 0, "reuses": 0, "gmres": 0}  # over the run's FactorReuse objects
    direct, gmres = factor_reuse.FactorReuse._direct, factor_reuse.FactorReuse._gmres

    def counted_direct(self, b, dx):
        counts["factorizations"] += 1
        return direct(self, b, dx)

    def counted_gmres(self, b, dx):
        converged = gmres(self, b, dx)
        counts["reuses"] += converged
        counts["gmres"] += self.ksp.getIterationNumber()
        return converged

    factor_reuse.FactorReuse._direct = counted_direct
    factor_reuse.FactorReuse._gmres = counted_gmres
    cpu, wall = time.process_time(), time.perf_counter()
    result = job_module.run_job(job, ".", progress=False)
    total = [time.process_time() - cpu, time.perf_counter() - wall]
    inner = [sum(v[k] for n, v in clock.items() if n not in ("import dolfinx", "imports"))
             for k in (0, 1)]  # fmt: skip
    clock["other"] = [total[0] - inner[0], total[1] - inner[1]]
    clock["run_job"] = total
    iterations = sum(i.iterations for i in result.increments)
    report = {"clock": clock, "iterations": iterations, "reuse": counts}
    print("PHASES " + json.dumps(report), file=sys.stderr)
    sys.stderr.flush()
    os._exit(0)


def _run(deck: Path, workdir: Path, petsc_options: str = "") -> tuple[dict, str]:
    """One run of ``deck`` in ``workdir`` (its own process): the driver's measurements and the
    process's standard output."""
    extra_env = {}
    if petsc_options:
        extra_env["PETSC_OPTIONS"] = petsc_options
        extra_env["GFORTRAN_UNBUFFERED_ALL"] = "1"  # MUMPS's lines before the driver's os._exit
    run = run_driver(__file__, deck, workdir, ROOT, "PHASES", extra_env)
    return run.data, run.stdout


def mumps_statistics(output: str) -> tuple[str, float]:
    """MUMPS's ordering, factor entries and operations per factorization from its statistics
    (``-ntf_mat_mumps_icntl_4 2``) as a sentence, and the operations; ("", 0) if it printed none.
    """
    ordering = re.findall(r"Ordering based on (\S+)", output)
    # MUMPS 5.5 prints "INFOG(29)", 5.7 "INFOG (29)"
    entries = re.findall(r"INFOG\s*\(29\)\s+Number of entries in factors\s*=\s*(\d+)", output)
    operations = re.findall(r"\(3\)\s+Operations in node elimination\s*=\s*(\S+)", output)
    if not operations:  # the analysis's estimate
        operations = re.findall(r"RINFOG\(1\) Operations during elimination[^=]*=\s*(\S+)", output)
    if not (ordering and entries and operations):
        return "", 0.0
    flops = float(operations[-1].replace("D", "E"))
    return (f"MUMPS (LDL^T or LU of the Jacobian): ordering {ordering[-1]}, "
            f"{int(entries[-1]):.3g} entries in the factors, {flops:.3g} operations per "
            "factorization", flops)  # fmt: skip


def table(runs: list[dict]) -> list[str]:
    """Markdown rows: each phase's median CPU and wall seconds over ``runs`` and its CPU share."""
    names = [n for n in (*PHASES, "run_job") if any(n in r["clock"] for r in runs)]
    median = {n: [statistics.median(r["clock"].get(n, [0, 0])[k] for r in runs) for k in (0, 1)]
              for n in names}  # fmt: skip
    whole = sum(median[n][0] for n in names if n != "run_job")
    rows = ["| phase | CPU [s] | wall [s] | share of CPU |", "|---|---|---|---|"]
    for name in names:
        cpu, wall = median[name]
        share = "" if name == "run_job" else f"{100 * cpu / whole:.0f} %"
        label = "`run_job` (all of the above from `deck` on)" if name == "run_job" else name
        rows.append(f"| {label} | {cpu:.3f} | {wall:.3f} | {share} |")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("deck", nargs="?", type=Path, metavar="DECK.inp",
                        help="deck (default: benchmarks/ccx_decks.py's punch_20)")  # fmt: skip
    parser.add_argument("--runs", type=int, default=5, help="timed runs (median)")
    parser.add_argument("--write", nargs="?", const=ROOT / "docs" / "performance.md", type=Path,
                        help="write its section of docs/performance.md (or this file)")  # fmt: skip
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from startup import compile_bytecode

    compile_bytecode(ROOT)
    with tempfile.TemporaryDirectory() as scratch:
        workdir = Path(scratch)
        if args.deck is None:
            import ccx_decks

            (punch,) = ccx_decks.select_decks(["punch_20"])
            punch.write(workdir)
            deck = workdir / "punch_20.inp"
        else:
            deck = workdir / args.deck.name
            deck.write_text(args.deck.read_text(encoding="latin-1"), encoding="latin-1")
        _run(deck, workdir)  # warm-up: the JIT cache
        loads = [os.getloadavg()[0]]
        runs = []
        for _ in range(args.runs):
            runs.append(_run(deck, workdir)[0])
            loads.append(os.getloadavg()[0])
        mumps, flops = mumps_statistics(_run(deck, workdir, "-ntf_mat_mumps_icntl_4 2")[1])
    solve = statistics.median(r["clock"]["linear solve"][0] for r in runs)
    iterations = runs[0]["iterations"]
    reuse = runs[0].get("reuse", {})
    factorizations = reuse.get("factorizations") or iterations  # fresh path: one per iteration
    lines = [
        f"`{deck.stem}`, {iterations} Newton iterations; median of {args.runs} runs after a "
        f"warm-up; 1-minute load average {min(loads):.1f} to {max(loads):.1f} on "
        f"{os.cpu_count()} cores.",
        "",
        *table(runs),
        "",
        f"The linear solve: {solve / max(iterations, 1):.3f} s CPU per Newton iteration"
        + (
            f" ({factorizations} factorization(s), {reuse['reuses']} correction(s) by GMRES "
            f"with an earlier factorization, {reuse['gmres']} GMRES iterations in all, "
            "`solvers/factor_reuse.py`)"
            if reuse.get("reuses")
            else ""
        )
        + ". "
        + (
            f"{mumps}: {flops * factorizations / solve / 1e9:.0f} GFlop/s over the "
            "factorizations, if they took all of the solve's time."
            if mumps
            else ""
        ),
    ]
    print("\n".join(lines))
    if args.write:
        import vs_ccx

        env = vs_ccx.environment()
        section = [
            f"## Phases of one run ({env['os']}, dolfinx {env['dolfinx']}, PETSc {env['petsc']})",
            "",
            f"Written by `.venv/bin/python benchmarks/job_phases.py --write` on {env['cpu']} "
            f"({env['cores']} cores), {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC: "
            "`python -m dolfinx_ntf run`'s work phase by phase, each phase's own time "
            "(`benchmarks/job_phases.py`).",
            "",
            *lines,
        ]
        vs_ccx.write_report(args.write, f"Phases of one run: {env['os']}", section)
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--driver"]:
        _driver(sys.argv[2])
    sys.exit(main())
