"""Fingerprint every deck and demo of a checkout: byte-level proof that a refactor changed nothing.

Every deck is run by ``python -m dolfinx_ntf run`` in its own temporary directory (serial); the JSON
file maps each deck to its exit status, its stderr (temporary paths masked), the sha256 of its
stdout (wall times masked) and the sha256 of the files it produced (``.dat``, ``.cel``, ``.frd``
without its date and time header lines, ``.sta``, ``.cvg``) and of its ``.inp`` text. The decks:

- ``data/...``: every ``.inp`` under ``tests/data/calculix`` that has a ``*STEP`` (include
  fragments have none; error decks are run too: their exit status and message are the record);
- ``crossval/``, ``friction/``: the decks of ``tests/data/calculix/crossval/cases.py`` and
  ``friction_cases.py`` (``hex20.py`` turns some of them into C3D20 decks), run with ``--tight``
  as the tests run them;
- ``dynamic/``: the ``*DYNAMIC`` decks of ``tests/test_dynamic_ccx.py``
  (``tests/data/calculix/dynamic/impact_deck.py``), ``--tight``;
- ``ties/``: the tie decks as ``tests/data/calculix/ties/make_tie_deck.py`` writes them;
- ``ccx_suite/``: CalculiX's own node-to-surface test decks (``benchmarks/ccx_suite.py``: package
  calculix-ccx-test), refused ones included (their message is recorded);
- ``bench/``: the decks of ``benchmarks/ccx_decks.py`` but ``SLOW_BENCH`` (its cross-validation
  decks are the ``crossval/`` ones and are not repeated): the ``quick`` ones and ``punch_20``,
  ``quarter_sphere`` (above 10000 dofs: ``--tangent auto`` takes ccx's symmetrized one there);
- ``options/``: two decks again with each non-default option of ``dolfinx_ntf run``.

Every demo of ``demos/`` runs with the tests' settings (``--coarse --quiet``, tests/test_demos.py);
its stdout and its returned summary are stored with wall times and temporary paths masked.

The checkout is ``--pythonpath DIR`` (default: the first entry of ``$PYTHONPATH``, else this
script's repository): its ``dolfinx_ntf`` is imported ahead of the venv's editable install, and
its ``tests/data``, ``benchmarks`` and ``demos`` are used. The header records which
``dolfinx_ntf/__init__.py`` the runs and the deck writers imported; the script stops if it is not
the checkout's.

    .venv/bin/python scripts/fingerprint_decks.py --pythonpath /work/wt-baseline -o base.json
    .venv/bin/python scripts/fingerprint_decks.py --compare base.json new.json
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import gzip
import hashlib
import importlib.util
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

FORMAT = 1
SUITE = Path("/usr/share/doc/calculix-ccx-test/examples/test")
OUTPUTS = (".dat", ".cel", ".frd", ".sta", ".cvg")
#: Options of ``dolfinx_ntf run`` other than the defaults, each run on the ``options/`` decks.
OPTION_SETS = {
    "stable_pairing": ["--stable-pairing"],
    "tangent_auto": ["--tangent", "auto"],
    "tangent_exact": ["--tangent", "exact"],
    "predictor_guarded": ["--predictor", "guarded"],
    "predictor_off": ["--predictor", "off"],
    "line_search": ["--line-search"],
    "robust": ["--robust"],
    "pair_after_predictor": ["--pair-after-predictor"],
}
OPTION_DECKS = ("data/two_cubes", "crossval/hex_two_pairs")
#: Demos and their arguments in tests/test_demos.py (``--output`` is added where they take it).
DEMOS = {
    "punch": ["--coarse", "--quiet"],
    "hertz_sphere": ["--coarse", "--quiet"],
    "impact": ["--coarse", "--quiet"],
    "sliding_block": ["--coarse", "--quiet"],
    "frictional_punch": ["--coarse", "--quiet"],
    "compare_continuum": ["--coarse", "--quiet"],
}
NO_OUTPUT_OPTION = {"compare_continuum"}
#: Benchmark decks left out: more than about 20 s (docs/performance.md, idle machine).
SLOW_BENCH = {"punch_30": "81k dofs, 17 s and 1.1 GB on an idle machine (more than about 20 s)"}
#: Summary entries that hold wall-clock seconds (masked when they are numbers, not lists).
WALL_KEYS = re.compile(r"^(time|wall_time|solve_time|time_\w+|\w+_seconds)$")
#: Wall times in printed lines: "(0.02 s)", "1.6 s)", "solve 1.2 s, total 3.4 s".
WALL_TIME = re.compile(
    r"(?<![\w.+-])\d+(?:\.\d+)?(?:e[-+]?\d+)? ?(?:s|ms|min)(?=[),;:]|\s*$)", re.M
)
FRD_DATE = re.compile(rb"^(\s*1U(?:DATE|TIME)).*$", re.M)
DEMO_WRAPPER = """
import importlib.util, json, sys
spec = importlib.util.spec_from_file_location("_demo_" + sys.argv[1], sys.argv[2])
module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
summary = module.main(sys.argv[3:])
sys.stdout.flush()
print("=== FINGERPRINT SUMMARY ===")
print(json.dumps(summary, sort_keys=True, default=repr))
"""


@dataclass
class Deck:
    """A deck to run: ``files`` maps relative paths to their bytes (the deck and its includes)."""

    key: str
    kind: str
    job: str
    files: dict[str, bytes]
    args: list[str] = field(default_factory=list)
    generated: bool = False


# ----------------------------------------------------------------------------- environment


def checkout_env(checkout: Path) -> dict[str, str]:
    """Environment of every subprocess: the checkout first on PYTHONPATH, one thread per BLAS."""
    env = dict(os.environ)
    old = [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p]
    env["PYTHONPATH"] = os.pathsep.join([str(checkout), *[p for p in old if p != str(checkout)]])
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        env[name] = "1"
    env["PYTHONHASHSEED"] = "0"
    env["MPLBACKEND"] = "Agg"
    return env


def imported_package(env: dict[str, str]) -> str:
    """``dolfinx_ntf.__file__`` as ``python -m dolfinx_ntf`` sees it (from a neutral directory)."""
    with tempfile.TemporaryDirectory() as scratch:
        done = subprocess.run(
            [sys.executable, "-c", "import dolfinx_ntf; print(dolfinx_ntf.__file__)"],
            cwd=scratch,
            env=env,
            capture_output=True,
            text=True,
            check=True,
        )
    return done.stdout.strip()


def git_head(checkout: Path) -> str:
    """The checkout's commit, with ``+dirty`` if its tracked files differ from it."""
    try:
        head = subprocess.run(
            ["git", "-C", str(checkout), "rev-parse", "HEAD"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        dirty = subprocess.run(
            ["git", "-C", str(checkout), "status", "--porcelain", "-uno"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def load_module(name: str, path: Path):
    """Import the file ``path`` as module ``name`` (its directory goes on sys.path first)."""
    if str(path.parent) not in sys.path:
        sys.path.insert(1, str(path.parent))
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


# ----------------------------------------------------------------------------- deck collection

INCLUDE = re.compile(r"^\*INCLUDE\s*,\s*INPUT\s*=\s*(\S+?)\s*$", re.I | re.M)
STEP = re.compile(r"^\*STEP\b", re.I | re.M)


def _with_includes(deck: Path, root: Path) -> dict[str, bytes]:
    """The deck and every file it includes (recursively), by path relative to its directory.

    An include is looked up next to the including file, then next to the deck.
    """
    files: dict[str, bytes] = {}
    todo = [deck]
    while todo:
        path = todo.pop()
        relative = path.relative_to(root).as_posix()
        if relative in files:
            continue
        text = path.read_bytes()
        files[relative] = text
        for name in INCLUDE.findall(text.decode("latin-1")):
            for base in (path.parent, root):
                if (base / name).is_file():
                    todo.append((base / name).resolve())
                    break
    return files


def data_decks(tree: Path) -> tuple[list[Deck], dict[str, str]]:
    """Every ``.inp`` under tests/data/calculix with a ``*STEP``; the others are fragments."""
    base = tree / "tests" / "data" / "calculix"
    decks, skipped = [], {}
    for path in sorted(base.rglob("*.inp")):
        relative = path.relative_to(base).with_suffix("").as_posix()
        if not STEP.search(path.read_text(encoding="latin-1")):
            skipped[f"data/{relative}"] = "no *STEP: an include fragment"
            continue
        files = _with_includes(path.resolve(), path.parent.resolve())
        decks.append(Deck(f"data/{relative}", "data", path.stem, files))
    return decks, skipped


def _written(kind: str, name: str, write: Callable[[Path], object], args=()) -> Deck:
    """A deck that ``write(directory)`` writes as ``<directory>/<name>.inp``."""
    with tempfile.TemporaryDirectory() as scratch:
        write(Path(scratch))
        text = (Path(scratch) / f"{name}.inp").read_bytes()
    return Deck(f"{kind}/{name}", kind, name, {f"{name}.inp": text}, list(args), True)


def crossval_decks(tree: Path) -> list[Deck]:
    """cases.py and friction_cases.py (through hex20.py), run ``--tight`` like their tests."""
    crossval = tree / "tests" / "data" / "calculix" / "crossval"
    cases = load_module("cases", crossval / "cases.py")
    friction = load_module("friction_cases", crossval / "friction_cases.py")
    decks = [_written("crossval", c.name, c.write, ["--tight"]) for c in cases.CASES]
    decks += [_written("friction", c.name, c.write, ["--tight"]) for c in friction.CASES]
    return decks


def dynamic_decks(tree: Path) -> list[Deck]:
    """The four ``*DYNAMIC`` decks of tests/test_dynamic_ccx.py, ``--tight`` like the tests."""
    deck = load_module("impact_deck", tree / "tests/data/calculix/dynamic/impact_deck.py")
    write = deck.write_impact_deck

    def two(directory: Path) -> None:
        text = write(directory, "two", period=0.005, speed=0.0, load=-1.0).read_text()
        head, step = text.split("*STEP, INC=10000\n", 1)
        step = step.replace("0.0005, 0.005", "0.0005, 0.0025")
        text = head + "*STEP, INC=10000\n" + step + "*STEP, INC=10000\n" + step
        (directory / "two.inp").write_text(text)

    def jump(directory: Path) -> None:
        text = write(directory, "jump", period=0.005, speed=0.0).read_text()
        text = text.replace(
            "*NODE PRINT, NSET=NALL", "*BOUNDARY\nNTOP, 3, 3, -0.001\n*NODE PRINT, NSET=NALL"
        )
        (directory / "jump.inp").write_text(text)

    tight = ["--tight"]
    return [
        _written("dynamic", "impact", lambda d: write(d, period=0.04), tight),
        _written(
            "dynamic", "load", lambda d: write(d, "load", period=0.005, speed=0.0, load=-1.0), tight
        ),
        _written("dynamic", "two", two, tight),
        _written("dynamic", "jump", jump, tight),
    ]


def tie_decks(tree: Path) -> list[Deck]:
    """The tie decks as make_tie_deck.py writes them (the stored copies are ``data/ties/``)."""
    ties = load_module("make_tie_deck", tree / "tests/data/calculix/ties/make_tie_deck.py")
    decks = []
    for job in sorted(ties.DECKS):
        text = ties.deck_text(job).encode()
        decks.append(Deck(f"ties/{job}", "ties", job, {f"{job}.inp": text}, [], True))
    return decks


def suite_decks() -> list[Deck]:
    """CalculiX's node-to-surface test decks, found as benchmarks/ccx_suite.py finds them."""
    decks = []
    for source in sorted(SUITE.glob("*.inp*")):
        name = source.name.removesuffix(".gz").removesuffix(".inp")
        opener = gzip.open if source.suffix == ".gz" else open
        with opener(source, "rt", encoding="latin-1") as stream:
            text = stream.read()
        if re.search(r"TYPE\s*=\s*NODE\s*TO\s*SURFACE", text, re.IGNORECASE):
            decks.append(
                Deck(
                    f"ccx_suite/{name}", "ccx_suite", name, {f"{name}.inp": text.encode("latin-1")}
                )
            )
    return decks


def bench_decks(tree: Path, crossval_names: set[str]) -> tuple[list[Deck], dict[str, str]]:
    """The decks of benchmarks/ccx_decks.py but the cross-validation ones and ``SLOW_BENCH``."""
    bench = load_module("ccx_decks", tree / "benchmarks" / "ccx_decks.py")
    decks, skipped = [], {}
    for deck in bench.DECKS:
        if deck.name in crossval_names:
            skipped[f"bench/{deck.name}"] = f"the same deck as crossval/{deck.name}"
        elif deck.name in SLOW_BENCH:
            skipped[f"bench/{deck.name}"] = SLOW_BENCH[deck.name]
        else:
            decks.append(_written("bench", deck.name, deck.write))
    return decks, skipped


def option_decks(decks: list[Deck]) -> list[Deck]:
    """``OPTION_DECKS`` again with each of ``OPTION_SETS``."""
    by_key = {d.key: d for d in decks}
    out = []
    for key in OPTION_DECKS:
        deck = by_key[key]
        for label, args in OPTION_SETS.items():
            out.append(
                Deck(
                    f"options/{key.split('/')[-1]}-{label}",
                    "options",
                    deck.job,
                    deck.files,
                    [*deck.args, *args],
                    deck.generated,
                )
            )
    return out


# ----------------------------------------------------------------------------- normalisation


def mask_text(text: str, replacements: dict[str, str]) -> str:
    """Paths replaced by their placeholders (longest first), wall times by ``<t>``."""
    for path, placeholder in sorted(replacements.items(), key=lambda kv: -len(kv[0])):
        text = text.replace(path, placeholder)
    return WALL_TIME.sub("<t>", text)


def frd_bytes(data: bytes) -> bytes:
    """A ``.frd`` file without its date and time (the ``1UDATE`` and ``1UTIME`` header lines)."""
    return FRD_DATE.sub(rb"\1 <masked>", data)


def sha256(data: bytes) -> str:
    """Hex sha256."""
    return hashlib.sha256(data).hexdigest()


# ----------------------------------------------------------------------------- running


def run_deck(deck: Deck, env: dict[str, str], checkout: Path, timeout: float) -> dict:
    """Run one deck in a fresh directory; its fingerprint."""
    with tempfile.TemporaryDirectory(prefix="fingerprint-") as scratch:
        directory = Path(scratch)
        for relative, data in deck.files.items():
            (directory / relative).parent.mkdir(parents=True, exist_ok=True)
            (directory / relative).write_bytes(data)
        command = [sys.executable, "-m", "dolfinx_ntf", "run", deck.job, *deck.args]
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command, cwd=directory, env=env, capture_output=True, timeout=timeout
            )
            code, stdout, stderr = done.returncode, done.stdout, done.stderr
        except subprocess.TimeoutExpired as expired:
            code, stdout, stderr = "timeout", expired.stdout or b"", expired.stderr or b""
        seconds = time.perf_counter() - start
        replacements = {
            str(directory): "<RUN>",
            os.path.realpath(directory): "<RUN>",
            str(checkout): "<CHECKOUT>",
        }
        record = {
            "kind": deck.kind,
            "args": deck.args,
            "exit": code,
            "stderr": mask_text(stderr.decode("utf-8", "replace"), replacements),
            "stdout_sha256": sha256(
                mask_text(stdout.decode("utf-8", "replace"), replacements).encode()
            ),
            "files": {},
        }
        if deck.generated:
            record["files"][f"{deck.job}.inp"] = sha256(deck.files[f"{deck.job}.inp"])
        for suffix in OUTPUTS:
            path = directory / f"{deck.job}{suffix}"
            if path.is_file():
                data = path.read_bytes()
                record["files"][path.name] = sha256(frd_bytes(data) if suffix == ".frd" else data)
    record["_seconds"] = seconds
    return record


def mask_summary(value):
    """A demo summary with the wall-clock entries (numbers under ``WALL_KEYS``) masked."""
    if isinstance(value, list):
        return [mask_summary(v) if isinstance(v, dict) else v for v in value]
    if isinstance(value, dict):
        return {
            k: "<t>" if WALL_KEYS.match(k) and isinstance(v, (int, float)) else v
            for k, v in value.items()
        }
    return value


def run_demo(name: str, tree: Path, env: dict[str, str], checkout: Path, timeout: float) -> dict:
    """Run ``demos/<name>.py`` with the tests' settings; its masked stdout and summary."""
    with tempfile.TemporaryDirectory(prefix="fingerprint-") as scratch:
        args = list(DEMOS[name])
        if name not in NO_OUTPUT_OPTION:
            args += ["--output", str(Path(scratch) / "output")]
        command = [
            sys.executable,
            "-c",
            DEMO_WRAPPER,
            name,
            str(tree / "demos" / f"{name}.py"),
            *args,
        ]
        start = time.perf_counter()
        try:
            done = subprocess.run(
                command, cwd=scratch, env=env, capture_output=True, timeout=timeout
            )
            code, stdout, stderr = done.returncode, done.stdout, done.stderr
        except subprocess.TimeoutExpired as expired:
            code, stdout, stderr = "timeout", expired.stdout or b"", expired.stderr or b""
        seconds = time.perf_counter() - start
        replacements = {
            scratch: "<RUN>",
            os.path.realpath(scratch): "<RUN>",
            str(checkout): "<CHECKOUT>",
        }
        out = stdout.decode("utf-8", "replace")
        printed, _, summary_text = out.partition("=== FINGERPRINT SUMMARY ===\n")
        summary = None
        if summary_text.strip():
            summary = json.loads(mask_text(summary_text, {k: v for k, v in replacements.items()}))
            summary = mask_summary(summary)
        return {
            "exit": code,
            "stdout": mask_text(printed, replacements),
            "summary": summary,
            "stderr": mask_text(stderr.decode("utf-8", "replace"), replacements),
            "_seconds": seconds,
        }


# ----------------------------------------------------------------------------- main modes


def collect(tree: Path, kinds: set[str]) -> tuple[list[Deck], dict[str, str]]:
    """Every deck of the selected kinds, and the skipped files with the reason."""
    decks, skipped = [], {}
    if "data" in kinds or "options" in kinds:
        found, skipped_data = data_decks(tree)
        decks += found
        skipped.update(skipped_data)
    crossval_names: set[str] = set()
    if kinds & {"crossval", "friction", "bench", "options"}:
        found = crossval_decks(tree)
        crossval_names = {d.job for d in found if d.kind == "crossval"}
        decks += found
    if "dynamic" in kinds:
        decks += dynamic_decks(tree)
    if "ties" in kinds:
        decks += tie_decks(tree)
    if "ccx_suite" in kinds:
        decks += suite_decks()
    if "bench" in kinds:
        found, skipped_bench = bench_decks(tree, crossval_names)
        decks += found
        skipped.update(skipped_bench)
    if "options" in kinds:
        decks += option_decks(decks)
    return [d for d in decks if d.kind in kinds], skipped


KINDS = ("data", "crossval", "friction", "dynamic", "ties", "ccx_suite", "bench", "options")


def fingerprint(args: argparse.Namespace) -> int:
    """Run everything and write the JSON file."""
    checkout = Path(args.pythonpath).resolve()
    tree = Path(args.tree).resolve() if args.tree else checkout
    env = checkout_env(checkout)
    expected = str(checkout / "dolfinx_ntf" / "__init__.py")
    runner = imported_package(env)
    # the deck writers run in this process: the checkout goes ahead of the editable install
    sys.path.insert(0, str(checkout))
    for name in [m for m in sys.modules if m == "dolfinx_ntf" or m.startswith("dolfinx_ntf.")]:
        del sys.modules[name]
    import dolfinx_ntf

    writer = dolfinx_ntf.__file__
    if os.path.realpath(runner) != expected or os.path.realpath(writer) != expected:
        print(
            f"dolfinx_ntf comes from {runner} (runs) and {writer} (deck writers), not from "
            f"{expected}",
            file=sys.stderr,
        )
        return 2
    kinds = set(args.kinds or KINDS)
    start = time.perf_counter()
    decks, skipped = collect(tree, kinds)
    if args.only:
        decks = [d for d in decks if any(re.search(p, d.key) for p in args.only)]
    demos = (
        []
        if args.no_demos
        else [
            n for n in DEMOS if not args.only or any(re.search(p, f"demos/{n}") for p in args.only)
        ]
    )
    print(
        f"{len(decks)} decks written in {time.perf_counter() - start:.1f} s; running them "
        f"with {args.jobs} process(es)",
        file=sys.stderr,
    )

    def one_deck(deck: Deck) -> tuple[str, dict]:
        record = run_deck(deck, env, checkout, args.timeout)
        print(
            f"  {deck.key}: exit {record['exit']} ({record['_seconds']:.1f} s)",
            file=sys.stderr,
            flush=True,
        )
        return deck.key, record

    def one_demo(name: str) -> tuple[str, dict]:
        record = run_demo(name, tree, env, checkout, args.demo_timeout)
        print(
            f"  demos/{name}: exit {record['exit']} ({record['_seconds']:.1f} s)",
            file=sys.stderr,
            flush=True,
        )
        return name, record

    with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        deck_results = dict(pool.map(one_deck, decks))
        demo_results = dict(pool.map(one_demo, demos))
    seconds = {k: round(v.pop("_seconds"), 1) for k, v in deck_results.items()}
    seconds.update({f"demos/{k}": round(v.pop("_seconds"), 1) for k, v in demo_results.items()})
    counts: dict[str, int] = {}
    for deck in decks:
        counts[deck.kind] = counts.get(deck.kind, 0) + 1
    header = {
        "format": FORMAT,
        "checkout": str(checkout),
        "tree": str(tree),
        "git_head": git_head(checkout),
        "dolfinx_ntf_file_runs": runner,
        "dolfinx_ntf_file_deck_writers": writer,
        "python": sys.executable,
        "ccx_suite": str(SUITE),
        "counts": {**counts, "demos": len(demo_results)},
        "skipped": dict(sorted(skipped.items())),
        "normalised": [
            ".frd: the 1UDATE and 1UTIME header lines (date and time of the run)",
            "stdout, stderr, demo output: temporary directory -> <RUN>, checkout -> <CHECKOUT>, "
            "wall times ('1.6 s') -> <t>; demo summaries: wall-clock entries -> <t>",
            ".xdmf/.h5 are not fingerprinted (HDF5 files carry no stable bytes)",
        ],
    }
    result = {
        "header": header,
        "decks": dict(sorted(deck_results.items())),
        "demos": dict(sorted(demo_results.items())),
    }
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    Path(args.output).write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
    total = time.perf_counter() - start
    if args.timings:
        Path(args.timings).write_text(json.dumps({"total": round(total, 1), **seconds}, indent=1))
    failed = {k: v["exit"] for k, v in deck_results.items() if v["exit"] != 0}
    print(
        f"wrote {args.output}: {counts}, {len(demo_results)} demos, {total:.0f} s; non-zero "
        f"exits: {failed}",
        file=sys.stderr,
    )
    return 0


def _differences(a, b, where: str) -> list[str]:
    """Every difference between two JSON values, as lines."""
    if isinstance(a, dict) and isinstance(b, dict):
        lines = []
        for key in sorted(set(a) | set(b)):
            if key not in a:
                lines.append(f"{where}/{key}: only in B")
            elif key not in b:
                lines.append(f"{where}/{key}: only in A")
            else:
                lines += _differences(a[key], b[key], f"{where}/{key}")
        return lines
    if a == b:
        return []
    if isinstance(a, str) and isinstance(b, str) and ("\n" in a or "\n" in b):
        diff = difflib.unified_diff(a.splitlines(), b.splitlines(), "A", "B", lineterm="", n=1)
        return [f"{where}: text differs", *(f"    {line}" for line in list(diff)[:40])]
    return [f"{where}: {json.dumps(a)[:200]} != {json.dumps(b)[:200]}"]


def compare(path_a: str, path_b: str) -> int:
    """Print every difference of decks and demos (the headers are only shown); 1 if any."""
    a, b = (json.loads(Path(p).read_text()) for p in (path_a, path_b))
    for key in ("checkout", "git_head", "dolfinx_ntf_file_runs"):
        print(f"{key}: A {a['header'].get(key)}  B {b['header'].get(key)}")
    lines = []
    for part in ("decks", "demos"):
        lines += _differences(a.get(part, {}), b.get(part, {}), part)
    lines += _differences(a["header"].get("skipped"), b["header"].get("skipped"), "skipped")
    for line in lines:
        print(line)
    print(f"{sum(not line.startswith('    ') for line in lines)} difference(s)")
    return 1 if lines else 0


def main(argv: list[str] | None = None) -> int:
    """Command line."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("A.json", "B.json"),
        help="print the differences of two fingerprint files; exit 1 if any",
    )
    first = os.environ.get("PYTHONPATH", "").split(os.pathsep)[0]
    parser.add_argument(
        "--pythonpath",
        default=first or str(Path(__file__).resolve().parents[1]),
        help="checkout whose dolfinx_ntf is fingerprinted (default: the first "
        "PYTHONPATH entry, else this script's repository)",
    )
    parser.add_argument(
        "--tree",
        help="where tests/data, benchmarks and demos are read (default: the --pythonpath checkout)",
    )
    parser.add_argument("-o", "--output", default="fingerprints.json", help="JSON file to write")
    parser.add_argument("--kinds", nargs="+", choices=KINDS, help="deck kinds (default: all)")
    parser.add_argument("--only", nargs="+", metavar="REGEX", help="decks/demos whose key matches")
    parser.add_argument("--no-demos", action="store_true", help="decks only")
    parser.add_argument("--jobs", type=int, default=1, help="runs at a time (default 1: serial)")
    parser.add_argument("--timeout", type=float, default=300.0, help="seconds per deck")
    parser.add_argument("--demo-timeout", type=float, default=600.0, help="seconds per demo")
    parser.add_argument("--timings", help="also write the wall time of every run to this JSON")
    args = parser.parse_args(argv)
    if args.compare:
        return compare(*args.compare)
    with contextlib.suppress(KeyboardInterrupt):
        return fingerprint(args)
    return 130


if __name__ == "__main__":
    sys.exit(main())
