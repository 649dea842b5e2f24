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
module of the package is compiled again at each start (about 0.1 s); run ``python -m compileall
dolfinx_ntf`` first to measure what an installed package does.

    .venv/bin/python benchmarks/startup.py DECK.inp [DECK.inp ...] [--runs 7] [--checkout DIR]
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHASES = ("python", "import dolfinx", "imports", "deck", "model", "set-up", "job")


def _driver(argv: list[str]) -> int:
    """In the child: run ``main(argv)`` with hooks; print the marks (wall clock) as JSON."""
    marks = {"python": (time.time(), time.process_time())}
    import dolfinx

    marks["import dolfinx"] = (time.time(), time.process_time())
    import dolfinx.cpp.fem

    import dolfinx_ntf  # noqa: F401
    from dolfinx_ntf.calculix import job

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
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(checkout), env.get("PYTHONPATH")]))
    start = time.time()
    done = subprocess.run(
        [sys.executable, __file__, "--driver", deck.stem],
        cwd=workdir,
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    lines = [line for line in done.stderr.splitlines() if line.startswith("MARKS ")]
    if done.returncode != 0 or not lines:
        raise RuntimeError(f"{deck.name}: exit {done.returncode}\n{done.stderr[-2000:]}")
    return {name: (t - start, cpu) for name, (t, cpu) in json.loads(lines[-1][6:]).items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("decks", nargs="+", type=Path, metavar="DECK.inp")
    parser.add_argument("--runs", type=int, default=7, help="timed runs per deck (median)")
    parser.add_argument("--python", default="/usr/bin/python3", help="python of the floor")
    parser.add_argument("--json", type=Path, help="also write every measurement here")
    parser.add_argument("--checkout", type=Path, default=ROOT,
                        help="checkout whose dolfinx_ntf runs (default: this one)")  # fmt: skip
    args = parser.parse_args(argv)
    results = {}
    with tempfile.TemporaryDirectory() as scratch:
        for deck in args.decks:
            workdir = Path(scratch) / deck.stem
            workdir.mkdir()
            _run(deck.resolve(), workdir, args.checkout)  # warm-up: JIT cache
            runs, floors, loads = [], [], []
            for _ in range(args.runs):
                floors.append(_floor(args.python))
                runs.append(_run(deck.resolve(), workdir, args.checkout))
                loads.append(os.getloadavg()[0])
            results[deck.stem] = {"runs": runs, "floors": floors, "loads": loads}
    print(f"| deck | clock | floor | {' | '.join(PHASES)} | first assembly | above floor | load |")
    print("|---" * (len(PHASES) + 6) + "|")
    for name, data in results.items():
        for clock, k in (("wall", 0), ("cpu", 1)):
            ends = {p: statistics.median(r[p][k] for r in data["runs"]) for p in PHASES}
            floor = statistics.median(f[k] for f in data["floors"])
            steps, previous = [], 0.0
            for phase in PHASES:
                steps.append(f"{ends[phase] - previous:.3f}")
                previous = ends[phase]
            first = statistics.median(r["set-up"][k] for r in data["runs"])
            print(f"| {name} | {clock} | {floor:.3f} | {' | '.join(steps)} | {first:.3f} | "
                  f"{first - floor:+.3f} | {statistics.median(data['loads']):.1f} |")  # fmt: skip
    print(f"\nmedians of {args.runs} runs in seconds: each phase's own duration; first assembly "
          "from spawn (wall) or the process's CPU time by then; floor: python -c 'import "
          "dolfinx', alternating with the runs; load: 1-minute load average")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    if len(sys.argv) > 1 and sys.argv[1] == "--driver":
        sys.exit(_driver(sys.argv[2:]))
    sys.exit(main())
