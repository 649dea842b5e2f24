"""The deck runner's contact tangent (docs/method.md §7.2, §7.4): CalculiX's by default; with
``tangent="auto"`` its symmetrized one from ``SYMMETRIC_MIN_DOFS`` dofs on, factored by Cholesky,
the exact one below; ``--tangent`` chooses.

The tangent changes the Newton path, not the converged state: at round-off controls both give the
same displacements, and on these decks the same iterations.
"""

from __future__ import annotations

import logging
from pathlib import Path

from mpi4py import MPI

import cases
import numpy as np
import pytest

from dolfinx_ntf import __main__ as cli
from dolfinx_ntf.calculix import job as job_module
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.logs import details_logger

pytestmark = pytest.mark.serial


def _run(name: str, directory: Path, **kwargs):
    return run_job(name, directory, comm=MPI.COMM_SELF, progress=False, **kwargs)


class _Lines(logging.Handler):
    """Collects the messages of a logger (which may not propagate to the root logger)."""

    def __init__(self) -> None:
        super().__init__(logging.INFO)
        self.text = ""

    def emit(self, record: logging.LogRecord) -> None:
        self.text += record.getMessage() + "\n"


@pytest.mark.parametrize("name", ["hex_linear_pressure", "hex_curved_master"])
def test_ccx_tangent_is_factored_by_cholesky_and_converges_to_the_same_state(name, tmp_path):
    (case,) = [c for c in cases.CASES if c.name == name]
    case.write(tmp_path)
    exact = _run(name, tmp_path, tight=True, problem_options={"symmetric": False})
    logger, lines = logging.getLogger("dolfinx_ntf"), _Lines()
    levels = logger.level, details_logger.level
    logger.addHandler(lines)
    logger.setLevel(logging.INFO)
    details_logger.setLevel(logging.INFO)  # the solver line, whatever tests ran before
    try:
        ccx = _run(name, tmp_path, tight=True, problem_options={"symmetric": True})
    finally:
        logger.removeHandler(lines)
        logger.setLevel(levels[0])
        details_logger.setLevel(levels[1])
    assert "direct linear solver" in lines.text  # INFO lines are seen
    assert "instead of Cholesky" not in lines.text  # the Jacobian is symmetric: Cholesky kept
    assert [i.iterations for i in ccx.increments] == [i.iterations for i in exact.increments]
    for a, b in zip(ccx.increments, exact.increments):
        scale = np.abs(b.displacement).max()
        assert np.abs(a.displacement - b.displacement).max() <= 1e-9 * scale


def test_auto_keeps_the_exact_tangent_on_small_decks_ccx_s_on_large_ones(tmp_path, monkeypatch):
    (case,) = [c for c in cases.CASES if c.name == "hex_linear_pressure"]
    case.write(tmp_path)
    seen = []
    create = job_module.CalculixModel.create_problem

    def record(self, *args, **options):
        problem = create(self, *args, **options)
        seen.append((problem.symmetric, problem.projection_tangent))
        return problem

    monkeypatch.setattr(job_module.CalculixModel, "create_problem", record)
    _run("hex_linear_pressure", tmp_path)  # 369 dofs: the default is ccx's at any size
    _run("hex_linear_pressure", tmp_path, tangent="auto")
    _run("hex_linear_pressure", tmp_path, tangent="exact")
    monkeypatch.setattr(job_module, "SYMMETRIC_MIN_DOFS", 300)
    _run("hex_linear_pressure", tmp_path, tangent="auto")
    assert seen == [(True, "ccx"), (False, "exact"), (False, "exact"), (True, "exact")]
    with pytest.raises(ValueError, match="tangent 'other'"):
        _run("hex_linear_pressure", tmp_path, tangent="other")


CCX_PATH = {"tangent": "ccx", "line_search": False, "predictor": True, "guard_predictor": False}


@pytest.mark.parametrize(
    ("argv", "options"),
    [
        ([], CCX_PATH),
        (["--tangent", "exact"], {**CCX_PATH, "tangent": "exact"}),
        (
            ["--tangent", "auto", "--line-search"],
            {**CCX_PATH, "tangent": "auto", "line_search": True},
        ),
        (["--predictor", "guarded"], {**CCX_PATH, "guard_predictor": True}),
        (["--predictor", "off"], {**CCX_PATH, "predictor": False}),
        (
            ["--robust"],
            {"tangent": "auto", "line_search": True, "predictor": True, "guard_predictor": True},
        ),
    ],
)
def test_path_options_of_the_command_line(argv, options, monkeypatch, tmp_path):
    calls = []

    def fake_run_job(jobname, directory, **kwargs):
        calls.append(kwargs)
        raise ValueError("stop here")

    monkeypatch.setattr(job_module, "run_job", fake_run_job)
    assert cli.main(["run", str(tmp_path / "JOB"), *argv]) == cli.EXIT_INPUT
    (kwargs,) = calls
    assert kwargs["problem_options"] == {
        "walk_from_previous_face": False,
        "contact_start_slope": False,
    }
    assert {key: kwargs[key] for key in options} == options
