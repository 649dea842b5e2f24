"""Start-up of ``python -m dolfinx_ntf run JOB``, phase by phase, against a bare ``import dolfinx``.

The floor is ``python -c "import dolfinx"`` (``--python``, default ``/usr/bin/python3``), timed
from just before the process is spawned to the end of the import. A run of the deck runner is
timed the same way, with marks at the end of each phase (the run is this file's driver: it imports
and calls ``dolfinx_ntf.__main__.main`` as ``python -m dolfinx_ntf`` does, with hooks that note the
time):

- ``python``: the interpreter is up (the driver's first line);
- ``import dolfinx``: the floor's own work, inside our process;
- ``imports``: ``dolfinx_ntf`` and ``dolfinx_ntf.calculix.job``;
- ``deck``: ``read_deck``; ``model``: ``build_model`` (mesh, spaces, forms' UFL, contact pairs);
- ``set-up``: the job's files, problem, Newton solver and writer, up to the first assembly (the
  forms are compiled or found in the JIT cache on the way);
- ``job``: the rest of the run (the Newton iterations, the outputs), to the end of ``main``.

Every deck runs ``--runs`` times after one untimed warm-up (which fills the JIT cache), alternating
with the floor; the table gives medians and the machine's load average. Serial. Python's bytecode
cache matters: with ``PYTHONDONTWRITEBYTECODE`` set and no ``__pycache__`` in the checkout every
module of the package is compiled again at each start (about 0.1 s CPU, 0.2 s wall), which an
installed package (and the floor's dolfinx, compiled by Debian) never does: every checkout timed
here is byte-compiled first (:func:`compile_bytecode`).

    .venv/bin/python benchmarks/startup.py [DECK.inp ...] [--runs 7] [--baseline DIR]
    .venv/bin/python benchmarks/startup.py --baseline DIR --batch --write   # docs/performance.md
"""

from __future__ import annotations

import argparse
import compileall
import gc
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from driver_run import run_driver

ROOT = Path(__file__).resolve().parents[1]
PHASES = ("python", "import dolfinx", "imports", "deck", "model", "set-up", "job")


def compile_bytecode(checkout: Path) -> None:
    """Byte-compile ``checkout``'s package into its ``__pycache__`` folders (ignored by git).

    Then its start-up is that of an installed package, as the floor's (Debian's dolfinx comes
    compiled), also where ``PYTHONDONTWRITEBYTECODE`` keeps Python from writing the cache itself.
    """
    if not compileall.compile_dir(str(checkout / "dolfinx_ntf"), quiet=1):
        raise RuntimeError(f"{checkout}: dolfinx_ntf does not compile")


def _driver(argv: list[str]) -> int:
    """In the child: run ``main(argv)`` with hooks; print the marks (wall clock) as JSON."""
    marks = {"python": (time.time(), time.process_time())}
    import dolfinx

    marks["import dolfinx"] = (time.time(), time.process_time())
    import dolfinx.cpp.fem

    gc.disable()  # as python -m dolfinx_ntf run does while it imports; it freezes what they made
    import dolfinx_ntf  # noqa: F401
    from dolfinx_ntf.calculix import job

    gc.freeze()
    gc.enable()
    marks["imports"] = (time.time(), time.process_time())

    def after(name: str, function):
        def hooked(*args, **kwargs):
            value = function(*args, **kwargs)
            marks.setdefault(name, (time.time(), time.process_time()))
            return value

        return hooked

    job.read_deck = after("deck", job.read_deck)
    job.build_model = after("model", job.build_model)
    for name in ("assemble_vector", "assemble_matrix", "assemble_scalar"):
        for module in (dolfinx.cpp.fem, getattr(dolfinx.cpp.fem, "petsc", None)):
            if module is not None and hasattr(module, name):
                original = getattr(module, name)

                def first(*args, _original=original, **kwargs):
                    marks.setdefault("set-up", (time.time(), time.process_time()))
                    return _original(*args, **kwargs)

                setattr(module, name, first)
    from dolfinx_ntf.__main__ import main

    status = main(["run", *argv])
    marks["job"] = (time.time(), time.process_time())
    print("MARKS " + json.dumps(marks), file=sys.stderr)
    return status


def _floor(python: str) -> tuple[float, float]:
    """Wall seconds from spawning ``python -c "import dolfinx"`` to the end of the import, and
    the CPU seconds of the process by then."""
    start = time.time()
    done = subprocess.run(
        [python, "-c", "import time, dolfinx; print(time.time(), time.process_time())"],
        capture_output=True,
        text=True,
        check=True,
    )
    wall, cpu = map(float, done.stdout.split()[-2:])
    return wall - start, cpu


def _run(deck: Path, workdir: Path, checkout: Path) -> dict[str, tuple[float, float]]:
    """One timed run of ``deck`` in ``workdir``: the end of each phase, wall seconds after
    spawning and CPU seconds of the process."""
    shutil.copy(deck, workdir / deck.name)
    run = run_driver(__file__, deck, workdir, checkout, "MARKS")
    return {name: (t - run.start, cpu) for name, (t, cpu) in run.data.items()}


def _table(results: dict[str, dict]) -> list[str]:
    """Phase durations per checkout, deck and statistic (Markdown): the median and the least
    wall time (the least is the one a busy machine disturbs least), the median CPU time."""
    lines = [
        f"| checkout | deck | statistic | floor | {' | '.join(PHASES)} | first assembly "
        "| above floor | load |",
        "|---" * (len(PHASES) + 7) + "|",
    ]
    for label, data in results.items():
        checkout, name = label.split(" ", 1)
        for what, k, pick in (("wall, median", 0, statistics.median), ("wall, least", 0, min),
                              ("CPU, median", 1, statistics.median)):  # fmt: skip
            ends = {p: [r[p][k] for r in data["runs"]] for p in PHASES}
            steps, previous = [], [0.0] * len(data["runs"])
            for phase in PHASES:
                steps.append(f"{pick([e - b for e, b in zip(ends[phase], previous)]):.3f}")
                previous = ends[phase]
            floor = pick(f[k] for f in data["floors"])
            first = pick(ends["set-up"])
            lines.append(f"| {checkout} | `{name}` | {what} | {floor:.3f} | {' | '.join(steps)} "
                         f"| {first:.3f} | {first - floor:+.3f} "
                         f"| {statistics.median(data['loads']):.1f} |")  # fmt: skip
    return lines


def _suite_decks(directory: Path) -> list[str]:
    """Write the suite decks dolfinx_ntf reads (``vs_ccx.suite_decks``) into ``directory``."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import vs_ccx

    names = []
    for deck in vs_ccx.suite_decks():
        (directory / deck.name).mkdir()
        deck.write(directory / deck.name)
        names.append(str(directory / deck.name / deck.name))
    return names


def _timed(command: list[str], env: dict[str, str]) -> tuple[float, float, int]:
    """Wall and CPU seconds (children's user + system) of ``command``, and its exit status."""
    before = os.times()
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, check=False)
    wall = time.perf_counter() - start
    after = os.times()
    cpu = after.children_user + after.children_system - before.children_user
    return wall, cpu - before.children_system, done.returncode


def _batch(checkout: Path, runs: int) -> list[str]:
    """The suite decks one process each against one ``run JOB1 JOB2 ...`` (Markdown lines)."""
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(checkout), env.get("PYTHONPATH")]))
    command = [sys.executable, "-m", "dolfinx_ntf", "run"]
    with tempfile.TemporaryDirectory() as scratch:
        jobs = _suite_decks(Path(scratch))
        if not jobs:
            return []
        _timed([*command, *jobs], env)  # warm-up: JIT cache
        separate, batch = [], []
        for _ in range(runs):
            walls, cpus = [], []
            for job in jobs:
                wall, cpu, _ = _timed([*command, job], env)
                walls.append(wall)
                cpus.append(cpu)
            separate.append((sum(walls), sum(cpus)))
            wall, cpu, _ = _timed([*command, *jobs], env)
            batch.append((wall, cpu))
    names = ", ".join(f"`{Path(j).name}`" for j in jobs)
    median = statistics.median
    return [
        f"CalculiX's test-suite decks that dolfinx_ntf reads ({names}): one process per deck "
        f"against one `python -m dolfinx_ntf run JOB1 JOB2 ...` (medians of {runs} alternating "
        "runs, load as above):",
        "",
        "| how | wall [s] | CPU [s] | per deck wall [s] |",
        "|---|---|---|---|",
        f"| one process per deck | {median(w for w, _ in separate):.2f} "
        f"| {median(c for _, c in separate):.2f} "
        f"| {median(w for w, _ in separate) / len(jobs):.2f} |",
        f"| one process, {len(jobs)} jobs | {median(w for w, _ in batch):.2f} "
        f"| {median(c for _, c in batch):.2f} | {median(w for w, _ in batch) / len(jobs):.2f} |",
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("decks", nargs="*", type=Path, metavar="DECK.inp",
                        help="decks (default: two_cubes and punch_20)")  # fmt: skip
    parser.add_argument("--runs", type=int, default=7, help="timed runs per deck (median)")
    parser.add_argument("--python", default="/usr/bin/python3", help="python of the floor")
    parser.add_argument("--json", type=Path, help="also write every measurement here")
    parser.add_argument("--checkout", type=Path, default=ROOT,
                        help="checkout whose dolfinx_ntf runs (default: this one)")  # fmt: skip
    parser.add_argument("--baseline", type=Path,
                        help="a checkout to compare (before), alternately")  # fmt: skip
    parser.add_argument("--batch", action="store_true",
                        help="also time the suite decks: one process each, one batch")  # fmt: skip
    parser.add_argument("--write", nargs="?", const=ROOT / "docs" / "performance.md", type=Path,
                        help="write the section of docs/performance.md (or this file)")  # fmt: skip
    args = parser.parse_args(argv)
    checkouts = {"this": args.checkout.resolve()}
    if args.baseline:
        checkouts = {"before": args.baseline.resolve(), "after": args.checkout.resolve()}
    for checkout in checkouts.values():
        compile_bytecode(checkout)
    results: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as scratch:
        decks = [d.resolve() for d in args.decks]
        if not decks:
            sys.path.insert(0, str(ROOT / "benchmarks"))
            import ccx_decks

            (punch,) = ccx_decks.select_decks(["punch_20"])
            punch.write(Path(scratch))
            decks = [ROOT / "tests" / "data" / "calculix" / "two_cubes.inp",
                     Path(scratch) / "punch_20.inp"]  # fmt: skip
        for deck in decks:
            for label, checkout in checkouts.items():
                workdir = Path(scratch) / label / deck.stem
                workdir.mkdir(parents=True)
                _run(deck, workdir, checkout)  # warm-up: JIT cache
                results[f"{label} {deck.stem}"] = {"runs": [], "floors": [], "loads": []}
            for _ in range(args.runs):
                for label, checkout in checkouts.items():
                    data = results[f"{label} {deck.stem}"]
                    data["floors"].append(_floor(args.python))
                    data["runs"].append(_run(deck, Path(scratch) / label / deck.stem, checkout))
                    data["loads"].append(os.getloadavg()[0])
    lines = _table(results)
    notes = (
        f"{args.runs} runs per checkout and deck after one warm-up run (the JIT cache is warm), in "
        "seconds: each phase's own duration (median, or least, over the runs); `first "
        "assembly`: from spawning the process (wall) or the process's CPU time by then; `floor`: "
        f"`python -c 'import dolfinx'` (`{args.python}`), run alternately with the decks; load: "
        "1-minute load average (2 and more on this machine's cores means other work shared them). "
        "Every checkout is byte-compiled first, as an installed package is (`compile_bytecode`). "
        "The driver imports the deck runner with the collector paused for every checkout (as "
        "`python -m dolfinx_ntf` does since the start-up work of issue 26), so a `before` "
        "checkout's `imports` leave out the full collector pass it paid (about 0.01 s)."
    )
    print("\n".join([*lines, "", notes]))
    batch = _batch(args.checkout.resolve(), max(1, args.runs // 2)) if args.batch else []
    if batch:
        print("\n" + "\n".join(batch))
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    if args.write:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        import vs_ccx

        env = vs_ccx.environment()
        section = [
            f"## Start-up and batch runs ({env['os']}, dolfinx {env['dolfinx']}, PETSc "
            f"{env['petsc']})",
            "",
            f"Written by `.venv/bin/python benchmarks/startup.py` on {env['cpu']} "
            f"({env['cores']} cores), {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC. "
            "Phases of `python -m dolfinx_ntf run JOB` (`benchmarks/startup.py`): `python` the "
            "interpreter up, `import dolfinx` as the floor does, `imports` dolfinx_ntf and its "
            "deck runner, `deck` read_deck, `model` build_model, `set-up` the job's files, "
            "problem, solver and writer up to the first assembly (forms from the JIT cache), "
            "`job` the rest of the run to the end of `main` (the exit is not included).",
            "",
            *lines,
            "",
            notes,
            "",
            "Above the floor: the modules the deck needs (`import dolfinx_ntf` loads its public "
            "names on first use, the deck runner the modules of dynamic, modal and coupled steps "
            "where such a step runs; about half of a module's cost is the creation of its "
            "dataclasses) and scipy's (the contact search needs the k-d tree of "
            "`scipy.spatial`, which imports `scipy.sparse`, `scipy.sparse.linalg` and "
            "`scipy.linalg`: about 0.06 s CPU), the deck (plain `*NODE` and `*ELEMENT` cards "
            "converted card-wide, all references checked in one search), the model (dolfinx "
            "mesh and spaces; dolfinx 0.5.2's scalar space of the components built once), and "
            "the set-up: the forms and elements, found in the JIT cache (each look-up: UFL's "
            "signature, ffcx's parameters printed to its log, a listing of the cache folder, "
            "about 2 ms per 4000 files there), the `.frd` mesh header, the contact problem (one "
            "pass of reference coordinates for all surfaces) and the XDMF mesh. Left out of the "
            "table: the exit. A bare `import dolfinx` takes about 0.2 s to exit (MPI and PETSc "
            "finalization, Python's teardown); `python -m dolfinx_ntf` finalizes PETSc and MPI "
            "and skips the rest of the teardown.",
            "",
        ]
        if batch:
            section += [*batch, ""]
        vs_ccx.write_report(args.write, "Start-up and batch runs", section)
        print(f"wrote {args.write}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--driver":
        sys.exit(_driver(sys.argv[2:]))
    sys.exit(main())
