"""Collective helpers: errors raised on every process, and the all-to-all exchange.

docs/method.md §14.4. A pairing step that fails on one process must fail on all, or the others
wait forever at their next collective call: :func:`collective_errors` and :func:`checkpoint` make
an exception on any process an exception on every process.
"""

from __future__ import annotations

import contextlib
import typing

from mpi4py import MPI

import numpy as np

from dolfinx_ntf import validation

__all__ = ["alltoallv", "checkpoint", "collective_errors", "collectively", "send_to_owners"]


def collectively(comm: MPI.Comm, function: typing.Callable, *args, **kwargs) -> typing.Any:
    """``function(*args, **kwargs)``; an exception on any process is raised on all. Collective.

    ``function`` must reach its own collective calls on all processes or raise on all before them.
    """
    result, error = None, None
    try:
        result = function(*args, **kwargs)
    except Exception as exc:  # an unexpected error on one process must not leave the others waiting
        error = exc
    validation.raise_collectively(comm, error)
    return result


def checkpoint(comm: MPI.Comm, error: Exception | None = None) -> None:
    """Raise on every process if any process has an ``error``. Collective.

    One allreduce of a flag; the message goes round only on failure. Inside
    :func:`collective_errors` every process calls it before each collective call (docs/method.md
    §14.4).
    """
    if comm.size == 1:
        return
    flag = np.array([int(error is not None)], dtype=np.int32)
    comm.Allreduce(MPI.IN_PLACE, flag, op=MPI.MAX)
    if flag[0]:
        try:
            validation.raise_collectively(comm, error)
        except Exception as exc:
            exc.raised_collectively = True  # the enclosing blocks do not check it again
            raise


@contextlib.contextmanager
def collective_errors(comm: MPI.Comm) -> typing.Iterator[None]:
    """An exception inside the block on any process is raised on all. Collective.

    Collective calls inside the block must be preceded by :func:`checkpoint` on every process: a
    process that failed leaves the block and meets the others at their next checkpoint (or at the
    block's end), where all raise.
    """
    try:
        yield
    except Exception as exc:
        if not getattr(exc, "raised_collectively", False):
            checkpoint(comm, exc)
        raise
    checkpoint(comm)


def alltoallv(comm: MPI.Comm, parts: list[np.ndarray], dtype: type, mpi_type: MPI.Datatype):
    """Send ``parts[q]`` (flat) to process ``q``; the received parts concatenated. Collective.

    The received parts follow the sending processes' order.
    """
    counts = np.array([p.size for p in parts], dtype=np.int64)
    received = np.asarray(comm.alltoall(counts.tolist()), dtype=np.int64)
    out = np.empty(int(received.sum()), dtype=dtype)
    send = np.concatenate(parts).astype(dtype) if parts else np.empty(0, dtype)
    comm.Alltoallv([send, counts, mpi_type], [out, received, mpi_type])
    return out


def send_to_owners(comm: MPI.Comm, keys: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """Send each ``keys[i]`` to process ``owner[i]``; returns the keys received. Collective."""
    order = np.argsort(owner, kind="stable")
    split = np.searchsorted(np.asarray(owner)[order], np.arange(1, comm.size))
    return alltoallv(comm, np.split(np.asarray(keys)[order], split), np.int64, MPI.INT64_T)
