"""ccx's own cubespring deck asks for ``*CONTACT FILE`` ``CDISP,CSTRESS``: the runner writes the
CONTACT block of the ``.frd`` as ccx does (issue: ccx reads four characters of each key)."""

import gzip
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf.calculix.ccx import run_ccx
from dolfinx_ntf.calculix.frd import read_frd
from dolfinx_ntf.calculix.job import run_job

CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")

pytestmark = [
    pytest.mark.serial,
    pytest.mark.ccx,
    pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed"),
    pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test"),
]


def test_cubespring_contact_block_matches_ccx(tmp_path):
    (source,) = CCX_TESTS.glob("cubespring.inp*")
    opener = gzip.open if source.suffix == ".gz" else open
    with opener(source, "rt", encoding="latin-1") as stream:
        text = stream.read()
    assert "CDISP" in text  # the deck spells the keys as ccx's manual does
    for code in ("ccx", "ntf"):
        (tmp_path / code).mkdir()
        (tmp_path / code / "cubespring.inp").write_text(text, encoding="latin-1")
    run_ccx(tmp_path / "ccx", "cubespring", timeout=300)
    assert run_job("cubespring", tmp_path / "ntf", comm=MPI.COMM_SELF, progress=False).completed
    ccx = read_frd(tmp_path / "ccx" / "cubespring.frd").blocks_named("CONTACT")
    ours = read_frd(tmp_path / "ntf" / "cubespring.frd").blocks_named("CONTACT")
    assert len(ours) == len(ccx) >= 1
    for theirs, mine in zip(ccx, ours):
        assert mine.components == theirs.components
        assert mine.time == theirs.time
        np.testing.assert_array_equal(mine.nodes, theirs.nodes)
        scale = np.abs(theirs.values).max(axis=0)
        assert scale.max() > 0
        np.testing.assert_allclose(mine.values, theirs.values, rtol=0, atol=1e-6 * scale.max())
