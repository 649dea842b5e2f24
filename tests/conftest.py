"""Pytest fixtures only (MPI-safe teardown); the shared builders are in ``tests/helpers``."""

import gc

from mpi4py import MPI

import pytest


@pytest.fixture(autouse=True)
def _collect_garbage():
    """Run collective destructors on all ranks together."""
    yield
    gc.collect()
    MPI.COMM_WORLD.barrier()
