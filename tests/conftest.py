"""Pytest fixtures only (MPI-safe teardown); the shared builders are in ``tests/helpers``."""

import gc
import logging

from mpi4py import MPI

import pytest


@pytest.fixture(autouse=True)
def _collect_garbage():
    """Run collective destructors on all ranks together."""
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()


@pytest.fixture
def progress_lines(monkeypatch):
    """Messages of the progress loggers on every process, levels restored afterwards (no stream
    handler: pytest's capture may close it)."""
    from dolfinx_ntf import logs  # here: the conftest imports no package at collection

    records = []

    class Keep(logging.Handler):
        def emit(self, record):
            records.append(record.getMessage())

    handler = Keep()
    monkeypatch.setattr(logs, "_handler", handler)  # log_progress adds no stream handler
    saved = (
        logs.logger.level,
        logs.logger.propagate,
        logs.newton_logger.level,
        logs.details_logger.level,
    )
    logs.logger.addHandler(handler)
    yield records
    logs.logger.removeHandler(handler)
    logs.logger.setLevel(saved[0])
    logs.logger.propagate = saved[1]
    logs.newton_logger.setLevel(saved[2])
    logs.details_logger.setLevel(saved[3])
