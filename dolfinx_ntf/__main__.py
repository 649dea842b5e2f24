"""Command line: ``python -m dolfinx_ntf run JOB [JOB ...] [options]`` (script ``dolfinx-ntf``).

Runs the CalculiX deck ``JOB.inp`` like ``ccx -i JOB``: ccx-like progress on the screen, results in
``JOB.dat``, ``JOB.frd``, ``JOB.sta``, ``JOB.cvg``, ``JOB.cel`` and ``JOB.xdmf`` next to the deck.
Exit status: 0 done, 1 bad or unsupported input or usage (the message names ``file:line``), 2 no
convergence (files keep the converged increments).

Several jobs run one after the other in one process, so that Python, the imports and the form
compiler's cache are paid for once (a parameter study, CalculiX's test suite): each job writes its
own files and gets its own status, a failing job does not stop the next one, and a summary lists
every job's status; the exit status is the largest of them (0 only if every job is done).

Under ``mpirun -n N`` every process runs the job and rank 0 writes the files and the messages
(docs/method.md §14.5); an error ends every process with the same status.
"""

from __future__ import annotations

import argparse
import gc
import logging
import os
import sys
import traceback
import typing
from pathlib import Path

__all__ = ["main"]

EXIT_OK, EXIT_INPUT, EXIT_NO_CONVERGENCE = 0, 1, 2


#: What ``--help`` says about the files, the exit statuses and the documentation.
_EPILOG = """\
files written next to JOB.inp (ccx 2.20's formats):
  JOB.dat   *NODE PRINT, *EL PRINT and *CONTACT PRINT results
  JOB.frd   *NODE FILE, *EL FILE and *CONTACT FILE results (ASCII, for cgx and converters)
  JOB.sta   progress, one row per increment attempt
  JOB.cvg   convergence, one row per Newton iteration
  JOB.cel   the contact elements of every pairing (when a request has CONTACT ELEMENTS)
  JOB.xdmf  displacement and contact pressure, clearance and status per increment (ParaView)

exit status:
  0  done
  1  bad or unsupported input, or bad usage (the message names file and line)
  2  no convergence (the files keep the converged increments)
  several JOBs: the largest status of the jobs (each job's status is listed at the end)

Under mpirun -n N every process runs the job, rank 0 writes the files and the
messages, and every process ends with the same status.

Documentation: `make docs`, then docs/_build/html/guide/decks.html (the deck runner
and its options) and guide/calculix.html (what is supported, differences to ccx);
sources in docs/guide/decks.md and docs/guide/calculix.md.
"""


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dolfinx-ntf",
        description="Node-to-face contact for dolfinx: run the CalculiX node-to-surface contact\n"
        "deck JOB.inp like `ccx -i JOB`, on one process or under mpirun:\n\n"
        "  dolfinx-ntf run JOB [JOB ...] [options]\n"
        "  python -m dolfinx_ntf run JOB [options]\n"
        "  mpirun -n N python -m dolfinx_ntf run JOB [options]\n\n"
        "`dolfinx-ntf run --help` lists the options.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser(
        "run",
        usage="dolfinx-ntf run JOB [JOB ...] [options]   "
        "(or: mpirun -n N python -m dolfinx_ntf run JOB)",
        help="run a CalculiX deck JOB.inp like ccx, writing JOB.dat, .frd, .sta, .cvg, .cel, .xdmf",
        description="Run the CalculiX deck JOB.inp like `ccx -i JOB` (JOB may have a directory\n"
        "and the .inp suffix): ccx-like progress on the screen, ccx's files next to the deck.\n"
        "Several JOBs run one after the other in one process (start-up paid once), each with\n"
        "its own files and status.",
        epilog=_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_argument("jobs", nargs="+", metavar="JOB", help="job name: reads JOB.inp")
    run.add_argument(
        "--tight",
        action="store_true",
        help="converge every increment to round-off (largest residual 1e-10 of the average force) "
        "instead of the deck's *CONTROLS / ccx defaults",
    )
    run.add_argument(
        "--stable-pairing",
        action="store_true",
        help="beyond ccx: a slave node keeps its master face while that face holds it within the "
        "search tolerance (no face ping-pong at re-pairings), ties decided in a frame of the "
        "model, "
        "and the penetration slope of the LINEAR law for springs touching at an increment start; "
        "default: ccx's search",
    )
    run.add_argument(
        "--tangent",
        choices=("ccx", "exact", "auto"),
        default="ccx",
        help="contact tangent: 'ccx' (default) ccx's: symmetrized (Cholesky or CG, about half the "
        "linear solver's work), interior-projection formula at projections clamped to a face "
        "edge, so that the iterations follow ccx's; 'exact' (LU or GMRES; fewer iterations at "
        "clamped projections); 'auto' ccx's symmetrized one from 10000 dofs on, exact below",
    )
    run.add_argument(
        "--area-weights",
        choices=("consistent", "ccx"),
        default="ccx",
        help="spring areas of 2D decks: 'ccx' (default) the fixed shares of the faces ccx expands "
        "2D edges into (1/2, 1/2; 26/100, 26/100, 48/100 on 3-node edges; rings by the edge's "
        "mean radius), which reproduce ccx's results; 'consistent' each edge's consistent "
        "shares (rings 2 pi int r phi ds), which pass the patch test",
    )
    run.add_argument(
        "--initial-acceleration",
        choices=("ccx", "exact"),
        default="ccx",
        help="start of *DYNAMIC steps: 'ccx' (default) the acceleration of an alpha-method "
        "increment of a tenth of the initial increment, which reproduces ccx's results; 'exact' "
        "M a0 = f_ext - f(u0) (the Python API's default)",
    )
    run.add_argument(
        "--predictor",
        choices=("ccx", "guarded", "off"),
        default="ccx",
        help="start each increment from ccx's extrapolation u_n + dt v_prev: 'ccx' (default) "
        "always, 'guarded' unless it brings slave nodes into contact that have no spring yet "
        "(then from u_n, which converges more often on growing contact zones), 'off' never",
    )
    run.add_argument(
        "--line-search",
        action="store_true",
        help="beyond ccx: backtrack along each Newton correction until the residual decreases "
        "(the Python API's default); default: ccx's full steps",
    )
    run.add_argument(
        "--robust",
        action="store_true",
        help="beyond ccx: the Python API's path, i.e. --tangent auto --predictor guarded "
        "--line-search (converges more often; iterations and contact elements then differ from "
        "ccx's)",
    )
    run.add_argument(
        "--pair-after-predictor",
        action="store_true",
        help="beyond ccx: pair again after the predictor has moved the nodes, so that nodes it "
        "pushes into the master start the increment with a spring; default: ccx's schedule",
    )
    run.add_argument(
        "--factorization",
        choices=("auto", "fresh", "reuse"),
        default="auto",
        help="the direct linear solver's factorizations: 'fresh' one per Newton iteration (the "
        "exact path); 'reuse' GMRES preconditioned by an earlier factorization while it "
        "converges in a few iterations, a fresh one otherwise (values agree to 1e-11 of the "
        "residual); 'auto' (default) reuse from 10000 dofs on",
    )
    run.add_argument(
        "--ccx-format",
        choices=("2.20", "2.23"),
        default="2.20",
        help="write the .dat and .frd files in this ccx version's format: 2.23 adds its "
        "S T E P / INCREMENT lines, its CELS title and its CONTACT component records; "
        "the values are ccx 2.20's either way (default 2.20)",
    )
    return parser


def _job_path(job: str) -> tuple[str, Path]:
    path = Path(job)
    name = path.name[:-4] if path.name.lower().endswith(".inp") else path.name
    return name, path.parent


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (several jobs: the largest of theirs)."""
    return _main(argv)


def _main(argv: list[str] | None, *, program: bool = False) -> int:
    """:func:`main`; ``program``: the process is this run's own (``python -m dolfinx_ntf``)."""
    try:
        args = _parser().parse_args(argv)
    except (
        SystemExit
    ) as exit_:  # argparse: --help exits 0, usage errors 2 (reserved for no convergence)
        return EXIT_OK if exit_.code in (0, None) else EXIT_INPUT
    logging.getLogger().setLevel(
        logging.WARNING
    )  # keep the JIT compiler's INFO lines off the screen
    from mpi4py import MPI

    if program:
        # what the imports make stays for good: no collector pass while they run (one full pass
        # over dolfinx's, UFL's and scipy's objects costs about 0.01 s), and none walks it later
        gc.disable()
        try:
            import dolfinx_ntf.calculix.job  # noqa: F401
        finally:
            gc.freeze()
            gc.enable()
    root = MPI.COMM_WORLD.rank == 0
    if len(args.jobs) == 1:
        return _run_one(args.jobs[0], args, MPI.COMM_WORLD)
    statuses = []
    for number, job in enumerate(args.jobs, start=1):
        if root:
            print(f"\n Job {number}/{len(args.jobs)}: {job}", flush=True)
        try:
            statuses.append(_run_one(job, args, MPI.COMM_WORLD))
        except Exception:  # an unexpected error of one job must not stop the others
            if root:
                traceback.print_exc()
            statuses.append(EXIT_INPUT)
        gc.collect()  # free this job's PETSc matrices and solvers before the next one
    if root:
        print(f"\n {len(args.jobs)} jobs, {statuses.count(EXIT_OK)} done:", flush=True)
        for job, status in zip(args.jobs, statuses):
            print(f"   {job}: {_STATUS_NAMES.get(status, 'failed')} (exit {status})")
    return max(statuses)


#: What each exit status of a job means, for the summary of several jobs.
_STATUS_NAMES = {EXIT_OK: "done", EXIT_INPUT: "bad input", EXIT_NO_CONVERGENCE: "no convergence"}


def _run_one(job: str, args: argparse.Namespace, comm: object) -> int:
    """Run one deck with the command line's options; its exit status (messages on rank 0)."""
    from dolfinx_ntf.calculix.job import JobError, run_job

    jobname, directory = _job_path(job)
    root = comm.rank == 0
    try:
        result = run_job(
            jobname,
            directory,
            comm=comm,
            tight=args.tight,
            problem_options={
                "walk_from_previous_face": args.stable_pairing,
                "contact_start_slope": args.stable_pairing,
            },
            tangent="auto" if args.robust else args.tangent,
            line_search=args.line_search or args.robust,
            predictor=args.predictor != "off",
            guard_predictor=args.predictor == "guarded" or args.robust,
            pair_after_predictor=args.pair_after_predictor,
            ccx_format=args.ccx_format,
            area_weights=args.area_weights,
            initial_acceleration=args.initial_acceleration,
            factorization=args.factorization,
        )
    except JobError as error:
        if root:
            print(
                f"\n *ERROR: {error}\n Results of the converged increments are kept in "
                f"{directory / jobname}.dat",
                file=sys.stderr,
            )
        return error.exit_code
    except (ValueError, NotImplementedError, OSError) as error:  # DeckError is a ValueError
        if root:
            print(f" *ERROR: {error}", file=sys.stderr)
        return EXIT_INPUT
    if root:
        print(
            f" Wrote {result.dat}" + (f", {result.cel}" if result.cel else "") + f", {result.frd} "
            f"(.sta, .cvg)"
            + (f" and {result.xdmf}" if result.xdmf else " (no .xdmf)")
            + f" ({len(result.increments)} increments, {result.wall_time:.1f} s)"
        )
    return EXIT_OK


def _exit(status: int) -> typing.NoReturn:
    """End the process with ``status``: PETSc and MPI finalized, Python's teardown skipped.

    The teardown (module clean-up, garbage collection) takes about 0.15 s after a deck. Every
    file of the job is closed by then; the standard streams and the logging handlers are flushed.
    PETSc's finalization still prints what its options ask for (``-log_view``).
    """
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    petsc = sys.modules.get("petsc4py.PETSc")
    if petsc is not None:
        petsc._finalize()
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is not None and mpi.Is_initialized() and not mpi.Is_finalized():
        mpi.Finalize()
    os._exit(status)


def _program() -> typing.NoReturn:
    """``python -m dolfinx_ntf``: :func:`main` in a process of its own, then :func:`_exit`."""
    _exit(_main(None, program=True))


if __name__ == "__main__":
    _program()
