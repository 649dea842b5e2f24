"""Direct against iterative linear solvers on the punch: the crossover (docs/method.md §14.7).

The punch of ``tests/helpers/blocks.py`` (a block pressed onto a larger clamped block, non-matching
meshes, LINEAR law) refined to ``--sizes`` cells per side of the lower block (the punch is 25 %
finer), from about 20k to 300k dofs. Every (size, solver, process count) runs in its own
``mpirun`` (this script starts them), so that peak memory is that of one solver. Each run solves
one increment to convergence with ``StaticStep`` (TIGHT controls) and reports:

- Newton iterations (they must not depend on the solver) and the mean wall time per iteration
  (slowest process; includes assembly, contact and the linear solve, and the first iteration's
  MUMPS analysis or GAMG set-up);
- CPU time per iteration summed over the processes (user + system, ``getrusage``): on a shared
  machine wall times include waiting for a core, CPU times much less so;
- peak resident memory per process, Krylov iterations of the last linear solve, the largest
  difference from the direct solver's displacements (relative to the largest displacement);
- the 1-min load average before and after each run.

Run from the repository root (about 15 minutes on 2 shared cores)::

    .venv/bin/python benchmarks/solvers.py                    # prints the table
    .venv/bin/python benchmarks/solvers.py --write            # and writes docs/performance.md
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
import typing
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx
import dolfinx.fem
import ufl

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import helpers  # the punch's mesh and residual
from contact_phases import _format_table

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc
from dolfinx_ntf.solvers import linear_solver

ROOT = Path(__file__).resolve().parents[1]
#: Pressure on the punch's top (E = 1000): a few per mille of strain.
PRESSURE = 20.0


def punch(n: int, comm: MPI.Comm) -> tuple[ntf.ContactProblem, dolfinx.fem.Constant]:
    """The punch of helpers with ``n`` cells per side of the lower block, the punch 25 % finer."""
    k, kz = max(2, round(0.75 * n)), max(2, round(0.625 * n))
    mesh, _, ft = helpers.two_blocks(
        comm,
        lower=((0, 0, -1), (1, 1, 1), (n, n, n)),
        upper=((0.2, 0.2, 0.0), (0.6, 0.6, 0.5), (k, k, kz)),
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    F = helpers.elastic_residual(u, v, ft, pressure)
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(helpers.LOWER_BOTTOM))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), bottom, V),
        component_bc(V, 0, ft.find(helpers.UPPER_TOP)),
        component_bc(V, 1, ft.find(helpers.UPPER_TOP)),
    ]
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, helpers.UPPER_BOTTOM),
        ntf.FacetSurface(ft, helpers.LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(helpers.YOUNGS_MODULUS)),
    )
    return ntf.ContactProblem(F, u, [pair], bcs), pressure


def _cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def worker(n: int, linear_solver: str, out_path: str) -> None:
    """Solve one increment of the punch (run under mpirun); rank 0 writes the JSON."""
    comm = MPI.COMM_WORLD
    load = os.getloadavg()[0]
    problem, pressure = punch(n, comm)
    V = problem.u.function_space
    dofs = 3 * V.dofmap.index_map.size_global
    newton = ntf.ContactNewtonSolver(comm, problem, linear_solver=linear_solver)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", PRESSURE * t), initial_increment=1.0)
    comm.barrier()
    cpu, start = _cpu(), time.perf_counter()
    results = step.run(newton, problem.u)
    wall = comm.allreduce(time.perf_counter() - start, op=MPI.MAX)
    cpu = comm.allreduce(_cpu() - cpu)
    iterations = [r.iterations for r in results]
    owned = V.dofmap.index_map.size_local
    X = V.tabulate_dof_coordinates()[:owned]
    rows = np.hstack([X, problem.u.x.array.reshape(-1, 3)[:owned]])
    gathered = comm.gather(rows)
    ksp = newton.krylov_solver
    memory = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # MB (Linux: kB)
    out = {
        "n": n,
        "processes": comm.size,
        "solver": linear_solver,
        "ksp": f"{ksp.getType()}+{ksp.getPC().getType()}",
        "ksp_iterations": ksp.getIterationNumber(),
        "dofs": dofs,
        "iterations": iterations,
        "wall": wall,
        "cpu": cpu,
        "memory": comm.allreduce(memory, op=MPI.MAX),
        "load": [load, os.getloadavg()[0]],
    }
    if comm.rank == 0:
        rows = np.vstack(gathered)
        # by position; coincident nodes of the two bodies (contact surface) by u_z
        x = np.round(rows[:, :3], 9)  # dof coordinates differ by round-off between partitions
        order = np.lexsort(np.vstack([rows[:, 5], x[:, 2], x[:, 1], x[:, 0]]))
        np.save(out_path + ".npy", rows[order, 3:])
        Path(out_path).write_text(json.dumps(out))
    newton.destroy()
    problem.destroy()


def _run(folder: Path, n: int, solver: str, processes: int) -> dict | None:
    """One worker in its own mpirun; None if it failed (e.g. out of memory)."""
    path = folder / f"{n}-{solver}-{processes}.json"
    if not path.is_file():
        command = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-n", str(processes)]
        command += [sys.executable, __file__, "--worker", str(path), "--sizes", str(n)]
        command += ["--solvers", solver]
        print(f"n = {n}, {solver}, {processes} process(es) ...", flush=True)
        env = {k: v for k, v in os.environ.items() if not k.startswith(("OMPI_", "PMIX_"))}
        if subprocess.run(command, cwd=ROOT, env=env).returncode != 0 or not path.is_file():
            return None
    result = json.loads(path.read_text())
    result["u"] = np.load(str(path) + ".npy")
    return result


def section(results: list[dict], threshold: int) -> list[str]:
    """The Markdown section for docs/performance.md."""
    header = [
        "dofs",
        "processes",
        "solver",
        "Newton iterations",
        "wall per iteration [s]",
        "CPU per iteration [s]",
        "peak memory per process [MB]",
        "Krylov its (last solve)",
        "max Δu / max u vs direct",
        "load before, after",
    ]
    rows = []
    for r in results:
        its = sum(r["iterations"])
        direct = [
            d
            for d in results
            if d["n"] == r["n"] and d["solver"] == "direct" and d["processes"] == r["processes"]
        ]
        diff = "-"
        if direct and r["solver"] != "direct":
            u0 = direct[0]["u"]
            diff = f"{np.abs(r['u'] - u0).max() / np.abs(u0).max():.1e}"
        rows.append(
            [
                str(r["dofs"]),
                str(r["processes"]),
                f"{r['solver']} ({r['ksp']})",
                ", ".join(map(str, r["iterations"])),
                f"{r['wall'] / its:.2f}",
                f"{r['cpu'] / its:.2f}",
                f"{r['memory']:.0f}",
                str(r["ksp_iterations"]) if r["solver"] != "direct" else "-",
                diff,
                f"{r['load'][0]:.1f}, {r['load'][1]:.1f}",
            ]
        )
    notes = []
    for processes in sorted({r["processes"] for r in results}):
        pairs = []
        for r in results:
            if r["processes"] != processes or r["solver"] != "direct":
                continue
            other = [
                i
                for i in results
                if i["n"] == r["n"] and i["processes"] == processes and i["solver"] != "direct"
            ]
            if other:
                per = [x["cpu"] / sum(x["iterations"]) for x in (r, other[0])]
                same = r["iterations"] == other[0]["iterations"]
                pairs.append((r["dofs"], per[0] / per[1], same))
        if pairs:
            ratios = ", ".join(f"{d}: {q:.2f}" for d, q, _ in pairs)
            same = "the same" if all(p[2] for p in pairs) else "**not** the same"
            notes.append(
                f"- {processes} process(es): CPU time per Newton iteration, direct over "
                f"iterative, by dofs: {ratios}; Newton iterations {same} with both solvers."
            )
    for solver in ("direct", "iterative"):
        largest = [r for r in results if r["solver"] == solver]
        if not largest:
            continue
        n = max(r["n"] for r in largest)
        runs = {r["processes"]: r for r in largest if r["n"] == n}
        if 1 in runs and 2 in runs:
            one, two = (runs[p] for p in (1, 2))
            per = [r["cpu"] / sum(r["iterations"]) for r in (one, two)]
            walls = [r["wall"] / sum(r["iterations"]) for r in (one, two)]
            notes.append(
                f"- {solver}, {one['dofs']} dofs, 2 processes against 1: wall time per "
                f"iteration {walls[0] / walls[1]:.2f}x faster (under different loads), CPU time "
                f"summed over the processes {per[1] / per[0]:.2f}x that of 1 process; on 2 idle "
                f"cores that would give at most {2 * per[0] / per[1]:.2f}x."
            )
    version = ".".join(map(str, PETSc.Sys.getVersion()))
    loads = [x for r in results for x in r["load"]]
    return [
        f"## Linear solvers: direct against iterative (dolfinx {dolfinx.__version__}, PETSc "
        f"{version})",
        "",
        "Written by `.venv/bin/python benchmarks/solvers.py --write` (docs/method.md §14.7): the "
        "punch of `tests/helpers/blocks.py` refined (hexahedra, LINEAR law, non-matching meshes), "
        "one "
        "increment solved to convergence with TIGHT controls, each run in its own `mpirun`. "
        "direct = MUMPS LU; iterative = GMRES (right-preconditioned, true residual reduced by "
        f"`ksp_rtol` = {linear_solver.ITERATIVE_PETSC_OPTIONS['ksp_rtol']:g}) with GAMG and the "
        "rigid-body modes of each body. Wall and CPU time per Newton iteration include assembly, "
        "contact and the first iteration's MUMPS analysis or GAMG set-up; CPU is summed over "
        "the processes. The machine (2 cores) was shared with other engineers' tests while "
        f"this ran (1-min load average {min(loads):.1f} to {max(loads):.1f}): wall times "
        "include waiting for a core, so read the CPU times for the crossover.",
        "",
        _format_table(header, rows),
        "",
        *notes,
        "",
        f'`linear_solver="auto"` (the default) uses the direct solver up to '
        f"`DIRECT_MAX_DOFS` = {threshold} dofs and the iterative one above.",
    ]


def main(argv: typing.Sequence[str] | None = None) -> int:
    """Command line entry point: launches the workers, prints (and writes) the table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[17, 24, 30, 36, 42])
    parser.add_argument("--solvers", nargs="+", default=["direct", "iterative"])
    parser.add_argument("--processes", type=int, nargs="+", default=[1, 2])
    parser.add_argument(
        "--direct-max-n", type=int, default=36, help="largest size run with the direct solver"
    )
    parser.add_argument("--write", action="store_true", help="write docs/performance.md")
    parser.add_argument("--results", help="folder for the workers' output; reused if present")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        worker(args.sizes[0], args.solvers[0], args.worker)
        return 0
    if MPI.COMM_WORLD.size != 1:
        parser.error("run without mpirun: the script starts its own mpirun per run")
    results = []
    with tempfile.TemporaryDirectory() as temporary:
        folder = Path(args.results or temporary)
        folder.mkdir(parents=True, exist_ok=True)
        for processes in args.processes:
            for n in args.sizes:
                for solver in args.solvers:
                    if solver == "direct" and n > args.direct_max_n:
                        continue
                    result = _run(folder, n, solver, processes)
                    if result is not None:
                        results.append(result)
    lines = section(results, linear_solver.DIRECT_MAX_DOFS)
    print("\n".join(lines))
    if args.write:
        import vs_ccx

        vs_ccx.write_report(ROOT / "docs" / "performance.md", "Linear solvers", lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
