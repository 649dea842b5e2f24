"""Several decks in one ``dolfinx_ntf run``: own files and status per job, nothing carried over.

A job that does not converge (``diverge``, exit 2) and a bad deck (exit 1) run before and between
good ones (``two_cubes``); each good job's files must be those of the same deck run alone, and the
logging handlers and PETSc's options database must be as before the batch.
"""

from __future__ import annotations

import logging
import shutil
import sys
from pathlib import Path

from petsc4py import PETSc

import pytest

from dolfinx_ntf import logs
from dolfinx_ntf.__main__ import main
from dolfinx_ntf.calculix import job as job_module

pytestmark = pytest.mark.serial

DATA = Path(__file__).parents[1] / "data" / "calculix"
FILES = (".dat", ".cel", ".sta", ".cvg")


def _deck(directory: Path, name: str, source: Path) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    shutil.copy(source / f"{name}.inp", directory / f"{name}.inp")
    return directory / name


def _handlers() -> list[list[logging.Handler]]:
    names = ("", "dolfinx_ntf", "dolfinx_ntf.newton", "dolfinx_ntf.details")
    return [list(logging.getLogger(name).handlers) for name in names]


class _CurrentStderr:
    """Writes to whatever ``sys.stderr`` is at the time (capsys swaps it per test phase)."""

    def write(self, text: str) -> int:
        return sys.stderr.write(text)

    def flush(self) -> None:
        sys.stderr.flush()


@pytest.fixture(autouse=True)
def _progress_to_current_stderr(monkeypatch):
    """The progress handler is made once per process, bound to the stderr of that moment."""
    handler = logs._handler  # ours only: pytest's own handlers are StreamHandlers too
    if handler is not None and handler in logging.getLogger("dolfinx_ntf").handlers:
        monkeypatch.setattr(handler, "stream", _CurrentStderr())


def test_batch_runs_every_job_with_its_own_files_and_status(tmp_path, capsys, monkeypatch):
    # without ccx's absolute residual floor, step 2 of "diverge" cannot converge (exit 2)
    monkeypatch.setattr(job_module, "CCX_RESIDUAL_FLOOR", 0.0)
    alone = _deck(tmp_path / "alone", "two_cubes", DATA)
    assert main(["run", str(alone)]) == 0
    capsys.readouterr()

    diverge = _deck(tmp_path / "a", "diverge", DATA / "model")
    first = _deck(tmp_path / "b", "two_cubes", DATA)
    bad = _deck(tmp_path / "c", "err_unknown_surface", DATA / "model")
    second = _deck(tmp_path / "d", "two_cubes", DATA)
    handlers, options = _handlers(), PETSc.Options().getAll()

    status = main(["run", str(diverge), str(first), str(bad), str(second) + ".inp"])

    assert status == 2  # the largest of 2, 0, 1, 0
    out, err = capsys.readouterr()
    assert "no convergence" in err and "err_unknown_surface.inp:34" in err
    assert "Traceback" not in err
    summary = out[out.index("4 jobs, 2 done:") :].splitlines()[1:]
    assert [line.split(": ", 1)[1] for line in summary] == [
        "no convergence (exit 2)",
        "done (exit 0)",
        "bad input (exit 1)",
        "done (exit 0)",
    ]
    for run in (first, second):
        for suffix in FILES:
            ours = run.with_suffix(suffix).read_bytes()
            assert ours == alone.with_suffix(suffix).read_bytes(), (run, suffix)
    assert diverge.with_suffix(".dat").stat().st_size > 0  # the converged increments of step 1
    assert not bad.with_suffix(".dat").exists()
    assert _handlers() == handlers
    assert PETSc.Options().getAll() == options


def test_batch_goes_on_after_an_unexpected_error(tmp_path, capsys, monkeypatch):
    """An exception that is not an input or convergence error: traceback, exit 1, next job runs."""
    first = _deck(tmp_path / "a", "two_cubes", DATA)
    second = _deck(tmp_path / "b", "two_cubes", DATA)
    real = job_module.build_model
    calls = []

    def failing_once(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:
            raise RuntimeError("injected failure")
        return real(*args, **kwargs)

    monkeypatch.setattr(job_module, "build_model", failing_once)
    assert main(["run", str(first), str(second)]) == 1
    out, err = capsys.readouterr()
    assert "RuntimeError: injected failure" in err
    assert not first.with_suffix(".dat").exists()
    assert second.with_suffix(".dat").exists()
    assert "2 jobs, 1 done:" in out
