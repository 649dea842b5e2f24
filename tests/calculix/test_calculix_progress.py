"""ccx's progress files JOB.sta and JOB.cvg (calculix/progress.py, docs/method.md §13.3)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from dolfinx_ntf.calculix import job as job_module
from dolfinx_ntf.calculix.job import JobError, run_job
from dolfinx_ntf.calculix.progress import CvgFile, StaFile, fortran_e

pytestmark = pytest.mark.serial

CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")


@pytest.mark.parametrize(
    "value, digits, text",
    [
        (0.25, 6, "0.250000E+00"),
        (1.0, 6, "0.100000E+01"),
        (0.0625, 6, "0.625000E-01"),
        (1858.04, 4, "0.1858E+04"),
        (0.99999, 4, "0.1000E+01"),
        (0.0, 4, "0.0000E+00"),
        (100.0, 4, "0.1000E+03"),
    ],
)
def test_fortran_e(value, digits, text):
    assert fortran_e(value, digits) == text


def test_rows_have_ccx_widths(tmp_path):
    sta = StaFile(tmp_path / "a.sta")
    sta.row(1, 3, 1, False, 5, 0.5, 0.5, 0.25)
    sta.row(1, 3, 2, True, 3, 0.5625, 0.5625, 0.0625)
    cvg = CvgFile(tmp_path / "a.cvg")
    cvg.rows(1, 1, 1, [(1, 9, 29.14, 0.01, 1.0, 1.0), (2, 9, 0.0, 1.0, 0.5, 1.0)])
    # rows as ccx 2.20 writes them
    assert (tmp_path / "a.sta").read_text().splitlines()[2:] == [
        "     1          3     1U    5  0.500000E+00  0.500000E+00  0.250000E+00",
        "     1          3     2     3  0.562500E+00  0.562500E+00  0.625000E-01",
    ]
    assert (tmp_path / "a.cvg").read_text().splitlines()[4:] == [
        "     1     1     1     1        9  0.2914E+06  0.1000E+03  0.0000E+00  0.0000E+00",
        "     1     1     1     2        9  0.0000E+00  0.5000E+02  0.0000E+00  0.0000E+00",
    ]


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
def test_contact1_sta_is_ccx_and_cvg_starts_like_ccx(tmp_path):
    shutil.copy(CCX_TESTS / "contact1.inp", tmp_path / "contact1.inp")
    run_job("contact1", tmp_path, progress=False)
    sta = (tmp_path / "contact1.sta").read_text().splitlines()
    cvg = (tmp_path / "contact1.cvg").read_text().splitlines()
    # ccx 2.20 on this deck (its .sta and the first .cvg row; later iterations take other paths)
    assert sta == [
        "SUMMARY OF JOB INFORMATION",
        "  STEP      INC     ATT  ITRS     TOT TIME     STEP TIME      INC TIME",
        "     1          1     1     6  0.100000E+01  0.100000E+01  0.100000E+01",
    ]
    assert cvg[0] == "SUMMARY OF C0NVERGENCE INFORMATION"
    assert len(cvg) == 4 + 6
    assert cvg[4] == (
        "     1     1     1     1        1  0.1858E+04  0.1000E+03  0.0000E+00  0.0000E+00"
    )
    assert [int(line.split()[3]) for line in cvg[4:]] == [1, 2, 3, 4, 5, 6]


def test_residual_floor_converges_like_ccx(tmp_path):
    """R_n = 1e-30 is below round-off; ccx 2.20 still converges (3, 2, 2, 2 iterations, its
    .sta), because a largest residual force below 1e-6 counts as zero: so does the deck runner."""
    deck = Path(__file__).parents[1] / "data" / "calculix" / "model" / "diverge.inp"
    shutil.copy(deck, tmp_path / "diverge.inp")
    run_job("diverge", tmp_path, progress=False)
    rows = (tmp_path / "diverge.sta").read_text().splitlines()[2:]
    assert [int(row.split()[3]) for row in rows] == [3, 2, 2, 2]


def test_failed_attempts_are_marked(tmp_path, monkeypatch):
    """A deck whose first attempt cannot converge: a U row in .sta, its iterations in .cvg."""
    deck = Path(__file__).parents[1] / "data" / "calculix" / "model" / "diverge.inp"
    shutil.copy(deck, tmp_path / "diverge.inp")
    monkeypatch.setattr(job_module, "CCX_RESIDUAL_FLOOR", 0.0)  # else R_n = 1e-30 converges
    with pytest.raises(JobError):  # the second step does not converge at its fixed increment
        run_job("diverge", tmp_path, progress=False)
    rows = (tmp_path / "diverge.sta").read_text().splitlines()[2:]
    assert rows and any(row[23] == "U" for row in rows)
    cvg = (tmp_path / "diverge.cvg").read_text().splitlines()[4:]
    failed = next(row for row in rows if row[23] == "U")
    step, increment, attempt = failed.split()[0], failed.split()[1], failed.split()[2][:-1]
    mine = [r for r in cvg if r.split()[:3] == [step, increment, attempt]]
    assert len(mine) == int(failed[24:29])
