"""benchmarks/job_phases.py and startup.compile_bytecode: MUMPS's statistics read from both
MUMPS versions' output, the phase table, the byte-compiled checkout."""

from __future__ import annotations

from pathlib import Path

import job_phases
import pytest
import startup

pytestmark = pytest.mark.serial

#: Lines of MUMPS 5.5's statistics (Debian 12) as ``-mat_mumps_icntl_4 2`` prints them.
MUMPS_55 = """
 Ordering based on PORD
 RINFOG(1) Operations during elimination (estim)= 1.568D+10
 INFOG(29)  Number of entries in factors    =        16042374
 ------(3)  Operations in node elimination  = 1.568D+10
"""

#: The same of MUMPS 5.7 (Debian 13), whose labels differ.
MUMPS_57 = """
 Ordering based on PORD
 RINFOG(1) Operations during elimination (estim)= 1.569D+10
 INFOG (29) Number of entries in factors            =        16066764
 ------ (3) Operations in node elimination          = 1.570D+10
"""


@pytest.mark.parametrize(
    ("output", "entries", "operations"),
    [(MUMPS_55, "1.6e+07", 1.568e10), (MUMPS_57, "1.61e+07", 1.570e10)],
)
def test_mumps_statistics_of_both_versions(output, entries, operations):
    text, flops = job_phases.mumps_statistics(output)
    assert flops == pytest.approx(operations)  # the count of the factorization, not the estimate
    assert "ordering PORD" in text and f"{entries} entries" in text


def test_mumps_statistics_without_them():
    assert job_phases.mumps_statistics("Job finished\n") == ("", 0.0)
    only_estimate = MUMPS_55.replace("------(3)  Operations in node elimination", "")
    assert job_phases.mumps_statistics(only_estimate)[1] == pytest.approx(1.568e10)


def test_phase_table_medians_and_shares():
    runs = [
        {"clock": {"deck": [1.0, 2.0], "linear solve": [3.0, 4.0], "run_job": [4.0, 6.0]}},
        {"clock": {"deck": [3.0, 2.0], "linear solve": [3.0, 8.0], "run_job": [6.0, 10.0]}},
        {"clock": {"deck": [2.0, 9.0], "linear solve": [6.0, 5.0], "run_job": [8.0, 14.0]}},
    ]
    rows = job_phases.table(runs)
    assert rows[:2] == ["| phase | CPU [s] | wall [s] | share of CPU |", "|---|---|---|---|"]
    assert rows[2] == "| deck | 2.000 | 2.000 | 40 % |"  # medians; 2 of 2 + 3 s CPU
    assert rows[3] == "| linear solve | 3.000 | 5.000 | 60 % |"
    assert rows[4].startswith("| `run_job`") and rows[4].endswith("| 6.000 | 10.000 |  |")
    assert len(rows) == 5  # phases no run timed are left out


def test_compile_bytecode_writes_the_cache_and_refuses_bad_source(tmp_path: Path):
    package = tmp_path / "dolfinx_ntf"
    package.mkdir()
    (package / "__init__.py").write_text("VALUE = 1\n")
    startup.compile_bytecode(tmp_path)
    assert list((package / "__pycache__").glob("__init__.*.pyc"))
    (package / "broken.py").write_text("def f(:\n")
    with pytest.raises(RuntimeError, match="does not compile"):
        startup.compile_bytecode(tmp_path)
