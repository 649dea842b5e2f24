"""Command line: ``python -m dolfinx_ntf run JOB [--tight]`` (console script ``dolfinx-ntf``).

Runs the CalculiX deck ``JOB.inp`` like ``ccx -i JOB``: ccx-like progress on the screen, results in
``JOB.dat``, ``JOB.cel`` and ``JOB.xdmf`` next to the deck. Exit status: 0 done, 1 bad or
unsupported input (the message names ``file:line``), 2 no convergence (files keep the converged
increments).

Under ``mpirun -n N`` every process runs the job and rank 0 writes the files and the messages
(docs/method.md §14.5); an error ends every process with the same status.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

__all__ = ["main"]

EXIT_OK, EXIT_INPUT, EXIT_NO_CONVERGENCE = 0, 1, 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dolfinx-ntf",
        description="Node-to-face contact for dolfinx: run CalculiX node-to-surface contact decks.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser(
        "run",
        help="run a CalculiX deck JOB.inp like ccx, writing JOB.dat, JOB.cel and JOB.xdmf",
        description="Run the CalculiX deck JOB.inp (JOB may have a directory and .inp suffix).",
    )
    run.add_argument("job", metavar="JOB", help="job name: reads JOB.inp")
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
        choices=("auto", "ccx", "exact"),
        default="auto",
        help="contact tangent: 'ccx' symmetrized like ccx (Cholesky or CG, about half the linear "
        "solver's work), 'exact' (LU or GMRES; fewer iterations at projections clamped to a face "
        "edge), 'auto' (default) ccx's from 10000 dofs on, exact below",
    )
    run.add_argument(
        "--predictor",
        choices=("guarded", "ccx", "off"),
        default="guarded",
        help="start each increment from ccx's extrapolation u_n + dt v_prev: 'guarded' (default) "
        "unless it brings slave nodes into contact that have no spring yet (then from u_n, which "
        "converges more often on growing contact zones), 'ccx' always, 'off' never",
    )
    run.add_argument(
        "--pair-after-predictor",
        action="store_true",
        help="beyond ccx: pair again after the predictor has moved the nodes, so that nodes it "
        "pushes into the master start the increment with a spring; default: ccx's schedule",
    )
    return parser


def _job_path(job: str) -> tuple[str, Path]:
    path = Path(job)
    name = path.name[:-4] if path.name.lower().endswith(".inp") else path.name
    return name, path.parent


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status."""
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

    from dolfinx_ntf.calculix.job import JobError, run_job

    jobname, directory = _job_path(args.job)
    root = MPI.COMM_WORLD.rank == 0
    try:
        result = run_job(
            jobname,
            directory,
            comm=MPI.COMM_WORLD,
            tight=args.tight,
            problem_options={
                "walk_from_previous_face": args.stable_pairing,
                "contact_start_slope": args.stable_pairing,
                **({} if args.tangent == "auto" else {"symmetric": args.tangent == "ccx"}),
            },
            predictor=args.predictor != "off",
            guard_predictor=args.predictor == "guarded",
            pair_after_predictor=args.pair_after_predictor,
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
            f"(.sta, .cvg) and {result.xdmf} "
            f"({len(result.increments)} increments, {result.wall_time:.1f} s)"
        )
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
