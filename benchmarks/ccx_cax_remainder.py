"""What remains between ccx's CAX decks and the deck runner (docs/method.md §23.3, "The remainder").

Runs the generated two-block decks of ``tests/helpers/ccx_2d_decks.py`` with ccx 2.20 and with
``run_job`` (ccx's area weights, the runner's default) and prints the largest difference of each
block relative to ccx's largest value (U after ccx's turn: ``u_r cos(1 deg)``, at corner nodes of
quadratic elements ``u_r (2 + cos(1 deg))/3``), varying what could cause the remainder: the mesh
size, the radius (the whole deck moved out by ``R0``), Poisson's ratio (0: no radial displacement in
the uniform state), contact or not, linear or quadratic elements. A second table compares the
runner's CAX4 with ccx's sector written out as a 3D deck (``tests/helpers/cax_sector.py``) at
several sector angles: at 2 degrees that deck is ccx's CAX4, and the difference to the runner falls
with the angle squared.

    .venv/bin/python benchmarks/ccx_cax_remainder.py
"""

from __future__ import annotations

import logging
import sys
import tempfile
from pathlib import Path

from mpi4py import MPI

import numpy as np

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.job import run_job

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
from helpers.cax_sector import SECOND_LINE, CaxBlocks  # noqa: E402
from helpers.ccx_2d_decks import Deck2D, dat_pairs  # noqa: E402

HALF_SECTOR = np.pi / 180.0


def _edit(path: Path, radius: float, nu: float) -> None:
    """Move every node out by ``radius`` and set Poisson's ratio ``nu`` in a generated deck."""
    head, rest = path.read_text().split("*NODE\n", 1)
    nodes, tail = rest.split("*ELEMENT", 1)
    moved = []
    for line in nodes.splitlines():
        n, x, y, z = (s.strip() for s in line.split(","))
        moved.append(f"{n}, {float(x) + radius!r}, {y}, {z}")
    tail = tail.replace("210000.0, 0.3", f"210000.0, {nu!r}")
    path.write_text(head + "*NODE\n" + "\n".join(moved) + "\n*ELEMENT" + tail)


def _corners(path: Path, element: str) -> np.ndarray:
    """2D nodes that are corners of an element (ccx expands them into three node lines)."""
    text = path.read_text().split("*ELEMENT", 1)[1].split("\n", 1)[1].split("*", 1)[0]
    corners = 3 if element[3] in "36" else 4
    rows = [line.split(",") for line in text.splitlines() if line.strip()]
    return np.unique([int(row[k]) for row in rows for k in range(1, corners + 1)])


def measure(deck: Deck2D, radius: float, nu: float, directory: Path) -> dict[str, float]:
    """Largest relative difference of each block at the last time, U turned as ccx prints it."""
    ccx_dir, ntf_dir = directory / "ccx", directory / "ntf"
    for d in (ccx_dir, ntf_dir):
        d.mkdir(parents=True)
        _edit(deck.write(d), radius, nu)
    run_ccx(ccx_dir, deck.name, timeout=120)
    run_job(deck.name, ntf_dir, comm=MPI.COMM_SELF, progress=False)
    quadratic = deck.element[3] in "68"
    corner = _corners(ccx_dir / f"{deck.name}.inp", deck.element)
    out = {}
    pairs = dat_pairs(ccx_dir, ntf_dir, deck.name)
    last = max(r.time for r, _ in pairs)
    for reference, mine in pairs:
        if reference.time != last or reference.name in ("RF_TOTAL", "S"):
            continue
        values = mine.values.copy()
        scale = np.abs(reference.values).max()
        if reference.name == "U":
            c = np.cos(HALF_SECTOR)
            three = np.isin(mine.labels, corner) if quadratic else np.zeros(len(mine.labels), bool)
            values[:, 0] *= np.where(three, (2 + c) / 3, c)
            out["U x"] = float(np.abs(values[:, 0] - reference.values[:, 0]).max() / scale)
            out["U z"] = float(np.abs(values[:, 1] - reference.values[:, 1]).max() / scale)
            continue
        columns = [0] if reference.name in ("CDIS", "CSTR") else slice(None)
        difference = np.abs(values[:, columns] - reference.values[:, columns]).max()
        out[reference.name] = float(difference / scale)
    return out


CASES = [
    ("CAX4, 4 x 2 / 3 x 2", Deck2D("cax4", "CAX4"), 0.0, 0.3),
    ("CAX4, 8 x 4 / 6 x 4", Deck2D("cax4", "CAX4", lower=(8, 4), upper=(6, 4)), 0.0, 0.3),
    ("CAX4, 16 x 8 / 12 x 8", Deck2D("cax4", "CAX4", lower=(16, 8), upper=(12, 8)), 0.0, 0.3),
    *[(f"CAX4, R0 = {r:g}", Deck2D("cax4", "CAX4"), r, 0.3) for r in (1.0, 3.0, 10.0, 100.0)],
    *[
        (
            f"CAX4 without contact, R0 = {r:g}, nu = {nu:g}",
            Deck2D("b4", "CAX4", contact=False),
            r,
            nu,
        )
        for nu in (0.3, 0.0)
        for r in (0.0, 1.0, 100.0)
    ],
    *[(f"CAX4, nu = 0, R0 = {r:g}", Deck2D("cax4", "CAX4"), r, 0.0) for r in (0.0, 1.0)],
    ("CAX8 without contact", Deck2D("b8", "CAX8", contact=False), 0.0, 0.3),
    ("CAX8", Deck2D("cax8", "CAX8"), 0.0, 0.3),
    ("CAX8 point forces", Deck2D("cax8", "CAX8", load="cload"), 0.0, 0.3),
    ("CAX6", Deck2D("cax6", "CAX6"), 0.0, 0.3),
    ("CAX8R", Deck2D("cax8r", "CAX8R"), 0.0, 0.3),
]

COLUMNS = ("U x", "U z", "RF", "CDIS", "CSTR", "CELS")


SECTOR_ANGLES = (4.0, 2.0, 1.0, 0.5, 0.25)


def _printed(directory: Path, name: str, deck: str, ccx: bool = True) -> np.ndarray:
    """The printed displacements of ``deck`` (local ones of a ``*TRANSFORM`` unflagged), by node."""
    directory.mkdir(parents=True)
    (directory / f"{name}.inp").write_text(deck)
    if ccx:
        run_ccx(directory, name, timeout=120)
    else:
        run_job(name, directory, comm=MPI.COMM_SELF, progress=False)
    path = directory / f"{name}.dat"
    path.write_text(path.read_text().replace(" L\n", "\n"))
    block = read_dat(path)[-1]
    order = np.argsort(block.labels)
    return block.labels[order], block.values[order]


def sector_table(directory: Path) -> None:
    """The runner's CAX4 against ccx's sector of each angle; ccx's CAX4 against its 2 degrees."""
    print(
        "\n| R0 | ccx CAX4 vs its 2-degree sector (u_r, u_z) | "
        + " | ".join(f"runner vs {a:g}-degree sector (u_r, u_z)" for a in SECTOR_ANGLES)
        + " |"
    )
    print("|---" * (len(SECTOR_ANGLES) + 2) + "|")
    for r0 in (0.0, 10.0):
        blocks = CaxBlocks(r0)
        base = directory / f"sector-{r0:g}"
        _, cax4 = _printed(base / "ccx", "cax4", blocks.cax4_deck())
        _, ours = _printed(base / "ntf", "cax4", blocks.cax4_deck(), ccx=False)
        scale = np.abs(cax4).max()
        cells = []
        for angle in SECTOR_ANGLES:
            labels, sector = _printed(base / f"{angle:g}", "sector", blocks.sector_deck(angle))
            first = sector[labels < SECOND_LINE]
            if angle == 2.0:
                same = (
                    np.abs(first[:, 0] * np.cos(HALF_SECTOR) - cax4[:, 0]).max() / scale,
                    np.abs(first[:, 2] - cax4[:, 1]).max() / scale,
                )
            cells.append(
                f"{np.abs(ours[:, 0] - first[:, 0]).max() / scale:.1e}, "
                f"{np.abs(ours[:, 1] - first[:, 2]).max() / scale:.1e}"
            )
        print(f"| {r0:g} | {same[0]:.1e}, {same[1]:.1e} | " + " | ".join(cells) + " |", flush=True)


def main() -> None:
    logging.getLogger("dolfinx_ntf").setLevel(logging.WARNING)
    print("| deck | " + " | ".join(COLUMNS) + " |")
    print("|---" * (len(COLUMNS) + 1) + "|")
    with tempfile.TemporaryDirectory() as tmp:
        for k, (label, deck, radius, nu) in enumerate(CASES):
            out = measure(deck, radius, nu, Path(tmp) / str(k))
            cells = [f"{out[c]:.1e}" if c in out else "" for c in COLUMNS]
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
        sector_table(Path(tmp))


if __name__ == "__main__":
    main()
