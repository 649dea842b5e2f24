"""ccx's 2D elements: the deck runner (natively 2D) against ccx 2.20 (expanded into 3D).

Runs the generated two-block decks of ``tests/helpers/ccx_2d_decks.py`` with ccx and with
``run_job`` and prints, per deck, the largest difference of each ``.dat`` block relative to ccx's
largest value of the block (last increment), as a Markdown table (docs/validation.md, "ccx's 2D
elements"). For CAX decks the column ``U turned`` compares after multiplying our ``u_r`` by
``cos(1 deg)``, what ccx prints for its sector's two node lines (docs/method.md §23).
A second table (``--friction`` prints it alone) takes the frictional decks, pressed then dragged
sideways with mu 0.2, over every increment, with the tangential columns of CDIS and CSTR.

    .venv/bin/python benchmarks/ccx_2d_decks.py [--friction]
"""

from __future__ import annotations

import logging
import sys
import tempfile
from pathlib import Path

from mpi4py import MPI

import numpy as np

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.job import run_job

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from helpers.ccx_2d_decks import Deck2D, block_difference, dat_pairs  # noqa: E402

#: (label, deck, run_job options)
CCX_AREAS = {"area_weights": "ccx"}  # the runner's default, named where it matters
CONSISTENT_AREAS = {"area_weights": "consistent"}

CASES = [
    ("CPE4 LINEAR", Deck2D("cpe4", "CPE4"), {}),
    ("CPE4 EXPONENTIAL", Deck2D("cpe4", "CPE4", law="EXPONENTIAL"), {}),
    ("CPE4 thickness 0.25", Deck2D("cpe4", "CPE4", thickness=0.25), {}),
    ("CPE3 LINEAR", Deck2D("cpe3", "CPE3"), {}),
    ("CPE4 pressure (*DLOAD)", Deck2D("cpe4", "CPE4", load="dload"), {}),
    ("CPE4 point forces (*CLOAD)", Deck2D("cpe4", "CPE4", load="cload"), {}),
    ("CPE6 LINEAR, consistent areas", Deck2D("cpe6", "CPE6"), CONSISTENT_AREAS),
    ("CPE6 LINEAR, area_weights=ccx", Deck2D("cpe6", "CPE6"), CCX_AREAS),
    ("CPE6 EXPONENTIAL, area_weights=ccx", Deck2D("cpe6", "CPE6", law="EXPONENTIAL"), CCX_AREAS),
    ("CPE8 LINEAR, area_weights=ccx", Deck2D("cpe8", "CPE8"), CCX_AREAS),
    ("CPE8R LINEAR, area_weights=ccx", Deck2D("cpe8r", "CPE8R"), CCX_AREAS),
    ("CPE8R EXPONENTIAL, area_weights=ccx", Deck2D("cpe8r", "CPE8R", law="EXPONENTIAL"), CCX_AREAS),
    ("CPE8R pressure, area_weights=ccx", Deck2D("cpe8r", "CPE8R", load="dload"), CCX_AREAS),
    ("CPS4 without contact", Deck2D("cps4", "CPS4", contact=False), {}),
    ("CPS4 LINEAR", Deck2D("cps4", "CPS4"), {}),
    ("CPS4 EXPONENTIAL", Deck2D("cps4", "CPS4", law="EXPONENTIAL"), {}),
    ("CPS3 LINEAR", Deck2D("cps3", "CPS3"), {}),
    ("CPS6 LINEAR, area_weights=ccx", Deck2D("cps6", "CPS6"), CCX_AREAS),
    ("CPS8R LINEAR, area_weights=ccx", Deck2D("cps8r", "CPS8R"), CCX_AREAS),
    ("CAX4 without contact", Deck2D("cax4", "CAX4", contact=False), {}),
    ("CAX4 LINEAR, consistent areas", Deck2D("cax4", "CAX4"), CONSISTENT_AREAS),
    ("CAX4 LINEAR, area_weights=ccx", Deck2D("cax4", "CAX4"), CCX_AREAS),
    ("CAX4 EXPONENTIAL, area_weights=ccx", Deck2D("cax4", "CAX4", law="EXPONENTIAL"), CCX_AREAS),
    ("CAX3 LINEAR, area_weights=ccx", Deck2D("cax3", "CAX3"), CCX_AREAS),
    ("CAX6 LINEAR, area_weights=ccx", Deck2D("cax6", "CAX6"), CCX_AREAS),
    ("CAX8 LINEAR, area_weights=ccx", Deck2D("cax8", "CAX8"), CCX_AREAS),
    ("CAX8R LINEAR, area_weights=ccx", Deck2D("cax8r", "CAX8R"), CCX_AREAS),
    ("CAX4 pressure, area_weights=ccx", Deck2D("cax4", "CAX4", load="dload"), CCX_AREAS),
    ("CAX4 point forces, area_weights=ccx", Deck2D("cax4", "CAX4", load="cload"), CCX_AREAS),
]

#: Pressed, then dragged sideways with friction mu 0.2 (stick slope 1e5): (label, deck)
FRICTION_CASES = [
    ("CPE4 friction", Deck2D("fcpe4", "CPE4", friction=(0.2, 1e5))),
    ("CPE8R friction", Deck2D("fcpe8r", "CPE8R", friction=(0.2, 1e5))),
    (
        "CPE4 friction, *CHANGE FRICTION mu 0.3",
        Deck2D("fchange", "CPE4", friction=(0.2, 1e5), change_mu=0.3),
    ),
    ("CPS4 friction", Deck2D("fcps4", "CPS4", friction=(0.2, 1e5))),
]

FRICTION_COLUMNS = (
    "U",
    "RF",
    "S",
    "CDIS n",
    "CDIS t1",
    "CDIS t2",
    "CSTR n",
    "CSTR t1",
    "CSTR t2",
    "CELS",
)

COLUMNS = ("U", "U turned", "RF", "S", "S zz", "CDIS", "CSTR", "CELS")


def measure(deck: Deck2D, options: dict, directory: Path) -> dict[str, float]:
    """Largest relative difference of each block at the last time."""
    ccx_dir, ntf_dir = directory / "ccx", directory / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir(parents=True)
        deck.write(d)
    run_ccx(ccx_dir, deck.name, timeout=120)
    run_job(deck.name, ntf_dir, comm=MPI.COMM_SELF, progress=False, **options)
    pairs = dat_pairs(ccx_dir, ntf_dir, deck.name)
    last = max(r.time for r, _ in pairs)
    out = {}
    for reference, mine in pairs:
        if reference.time != last or reference.name == "RF_TOTAL":
            continue
        if reference.name == "S":
            out["S"] = block_difference(reference, mine, [0, 1, 3])
            out["S zz"] = block_difference(reference, mine, [2])
            continue
        columns = [0] if reference.name in ("CDIS", "CSTR") else slice(None)
        out[reference.name] = block_difference(reference, mine, columns)
        if reference.name == "U" and deck.element.startswith("CAX"):
            turned = mine.values.copy()
            turned[:, 0] *= np.cos(np.pi / 180)
            scale = np.abs(reference.values).max()
            out["U turned"] = float(np.abs(turned - reference.values).max() / scale)
    return out


def measure_friction(deck: Deck2D, directory: Path) -> dict[str, float]:
    """Largest relative difference of each block (column) over every increment."""
    ccx_dir, ntf_dir = directory / "ccx", directory / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir(parents=True)
        deck.write(d)
    run_ccx(ccx_dir, deck.name, timeout=120)
    run_job(deck.name, ntf_dir, comm=MPI.COMM_SELF, progress=False)
    out: dict[str, float] = {}
    for reference, mine in dat_pairs(ccx_dir, ntf_dir, deck.name):
        if reference.name in ("CDIS", "CSTR"):
            for k, column in enumerate(("n", "t1", "t2")):
                key = f"{reference.name} {column}"
                out[key] = max(out.get(key, 0.0), block_difference(reference, mine, [k]))
        elif reference.name != "RF_TOTAL":
            out[reference.name] = max(
                out.get(reference.name, 0.0), block_difference(reference, mine)
            )
    return out


def _table(columns: tuple[str, ...]) -> None:
    print("| deck | " + " | ".join(columns) + " |")
    print("|---" * (len(columns) + 1) + "|")


def main() -> None:
    logging.getLogger("dolfinx_ntf").setLevel(logging.WARNING)
    if "--friction" not in sys.argv[1:]:
        _main_table()
        print()
    _table(FRICTION_COLUMNS)
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, deck) in enumerate(FRICTION_CASES):
            values = measure_friction(deck, Path(tmp) / str(k))
            cells = [f"{values[c]:.1e}" if c in values else "" for c in FRICTION_COLUMNS]
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


def _main_table() -> None:
    """The frictionless decks, last increment."""
    _table(COLUMNS)
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, deck, options) in enumerate(CASES):
            values = measure(deck, options, Path(tmp) / str(k))
            cells = [f"{values[c]:.1e}" if c in values else "" for c in COLUMNS]
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
