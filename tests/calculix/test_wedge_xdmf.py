"""``JOB.xdmf`` of a deck with C3D6 wedges (docs/method.md §30.6), serial and on 2 processes.

The wedge punch deck (a C3D8 block pressed by a punch of 12 wedges) writes its mesh with 12 XDMF
``Wedge`` and 25 ``Hexahedron`` cells; the displacement and the contact pressure in the file are
the ``.dat`` file's U and CSTR at the printed digits (both gathered in ccx order, so on any
number of processes). Of the wedges' element outputs only ``*EL PRINT`` S, E and PEEQ are
printed (at ccx's two C3D6 points, ``test_ccx_wedges.py``); ``*EL FILE`` stays refused.
"""

from __future__ import annotations

import logging
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.decks import DATA
from helpers.xdmf import read_xdmf

from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.outputs.xdmf_cells import XDMF_HEXAHEDRON, XDMF_WEDGE

COMM = MPI.COMM_WORLD


def _run(directory: Path, text: str, comm: MPI.Comm = COMM):
    if comm.rank == 0:
        directory.mkdir(parents=True, exist_ok=True)
        (directory / "wedge_punch.inp").write_text(text)
    comm.barrier()
    logger = logging.getLogger("dolfinx_ntf")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        return run_job("wedge_punch", directory, comm=comm, progress=False)
    finally:
        logger.setLevel(level)


@pytest.mark.mpi
def test_wedge_deck_writes_xdmf(tmp_path: Path) -> None:
    directory = Path(COMM.bcast(str(tmp_path), root=0)) / "wedges"
    text = (DATA / "wedge_punch.inp").read_text()
    result = _run(directory, text)
    assert result.completed and result.xdmf == directory / "wedge_punch.xdmf"
    if COMM.rank != 0:
        return
    deck = read_deck(directory / "wedge_punch.inp")
    points, cells, steps = read_xdmf(result.xdmf)
    assert np.array_equal(points, deck.node_coords)
    kinds = [kind for kind, _ in cells]
    assert kinds.count(XDMF_WEDGE) == deck.wedges.size == 12
    assert kinds.count(XDMF_HEXAHEDRON) == deck.num_elements - 12
    block = deck.elements["C3D8"]
    for (kind, nodes), element, corners in zip(cells, block.ids, block.connectivity):
        wedge = kind == XDMF_WEDGE
        assert wedge == (int(element) in deck.wedges)
        assert set(deck.node_ids[nodes].tolist()) == set(corners.tolist())
        if wedge:  # VTK's orientation: the first triangle's normal away from the second
            p = points[nodes]
            normal = np.cross(p[1] - p[0], p[2] - p[0])
            assert normal @ (p[3:].mean(0) - p[:3].mean(0)) < 0.0
    blocks = read_dat(directory / "wedge_punch.dat")
    assert [s["t"] for s in steps] == sorted({b.time for b in blocks})
    (u,) = [b for b in blocks if b.name == "U"]
    rows = deck.node_index(u.labels)
    largest = np.abs(u.values).max()
    assert np.abs(steps[-1]["displacement"][rows] - u.values).max() <= 1e-6 * largest
    (cstr,) = [b for b in blocks if b.name == "CSTR"]
    assert cstr.labels.size > 0
    pressure = steps[-1]["contact_pressure"][deck.node_index(cstr.labels), 0]
    assert np.abs(pressure - cstr.values[:, 0]).max() <= 1e-6 * np.abs(cstr.values[:, 0]).max()
    status = steps[-1]["contact_status"][:, 0]
    assert set(np.flatnonzero(status == 1.0).tolist()) <= set(deck.node_index(cstr.labels))


@pytest.mark.serial
def test_wedge_element_outputs_stay_refused(tmp_path: Path) -> None:
    """Wedge element outputs but S, E, PEEQ, ENER, SDV and ME are refused before the run
    (method §35, §41.4)."""
    text = (DATA / "wedge_punch.inp").read_text()
    text = text.replace("*CONTACT PRINT", "*EL FILE\nS, HFL\n*CONTACT PRINT")
    with pytest.raises(
        NotImplementedError,
        match=r"\*EL FILE S/HFL of C3D6 element \d+ is not supported",
    ):
        _run(tmp_path, text, MPI.COMM_SELF)
