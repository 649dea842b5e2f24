"""Progress output through Python's ``logging``, and the log lines of the libraries below.

dolfinx_ntf writes to the logger ``"dolfinx_ntf"`` at ``INFO``: one line per converged increment
(iterations, springs, face changes, residual, time), cutbacks and their reasons, warnings. Two
children carry more, quiet unless asked for: ``"dolfinx_ntf.details"`` has CalculiX's lines (each
attempt's increment size and step time, the spring count of every pairing, ADJUST, solver swaps;
the deck runner prints them as ccx does), ``"dolfinx_ntf.newton"`` one line per Newton iteration
(residual norm, correction norm, spring count). Nothing is printed until :func:`log_progress` adds a
handler (or the application configures ``logging`` itself and sets the children's levels).

Two libraries below print on their own, and are kept out of the way:
    - dolfinx's C++ log prints ``Newton solver did not converge`` warnings; the contact solver
      reports non-convergence itself (with the residuals), so it raises dolfinx's log level to
      ``ERROR`` while it solves (:func:`quiet_dolfinx`).
    - Debian's cffi compiles JIT forms through setuptools, whose log lines (``INFO:root:gcc ...``)
      go to the root logger; a filter on the root logger, installed when dolfinx_ntf is
      imported, routes them to ``"dolfinx_ntf.jit"`` at ``DEBUG`` instead.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator

from mpi4py import MPI

import dolfinx.log

__all__ = [
    "details_logger",
    "jit_logger",
    "log_progress",
    "logger",
    "newton_logger",
    "quiet_dolfinx",
    "route_compiler_lines",
]

#: Increments, attempts, pairings and convergence (``INFO``).
logger = logging.getLogger("dolfinx_ntf")
#: CalculiX's lines: attempts, the spring count of each pairing, ADJUST, solver swaps (``INFO``);
#: quiet (``WARNING``) unless :func:`log_progress` is called with ``details=True``.
details_logger = logging.getLogger("dolfinx_ntf.details")
details_logger.setLevel(logging.WARNING)
#: One line per Newton iteration (``INFO``); quiet (``WARNING``) unless :func:`log_progress` is
#: called with ``iterations=True``.
newton_logger = logging.getLogger("dolfinx_ntf.newton")
newton_logger.setLevel(logging.WARNING)
#: Compiler command lines of dolfinx's JIT (``DEBUG``); quiet unless its level is lowered, e.g.
#: ``logging.getLogger("dolfinx_ntf.jit").setLevel(logging.DEBUG)``.
jit_logger = logging.getLogger("dolfinx_ntf.jit")
jit_logger.setLevel(logging.WARNING)

_handler: logging.Handler | None = None


def log_progress(
    level: int = logging.INFO, *, iterations: bool = False, details: bool = False
) -> None:
    """Print dolfinx_ntf's progress lines on rank 0: one per increment.

    Args:
        level: Level of the ``"dolfinx_ntf"`` logger (``logging.INFO`` shows increments and
            cutbacks; ``logging.WARNING`` only problems).
        iterations: Also print one line per Newton iteration: residual norm (and its ratio to the
            first one), correction norm, number of contact springs.
        details: Also print CalculiX's lines: each attempt's increment size and step time, the
            spring count of every pairing, ADJUST moves, linear-solver swaps.
    """
    global _handler
    if _handler is None and MPI.COMM_WORLD.rank == 0:
        _handler = logging.StreamHandler()
        _handler.setFormatter(logging.Formatter("%(message)s"))
        logger.addHandler(_handler)
    logger.setLevel(level)
    logger.propagate = False
    newton_logger.setLevel(level if iterations else logging.WARNING)
    details_logger.setLevel(level if details else logging.WARNING)


@contextlib.contextmanager
def quiet_dolfinx() -> Iterator[None]:
    """Raise dolfinx's C++ log level to ``ERROR`` inside the context (restored afterwards)."""
    previous = dolfinx.log.get_log_level()
    # The numeric order of the levels differs between dolfinx 0.5.2 (loguru) and 0.9 (spdlog).
    if previous in (dolfinx.log.LogLevel.ERROR, dolfinx.log.LogLevel.OFF):
        yield
        return
    dolfinx.log.set_log_level(dolfinx.log.LogLevel.ERROR)
    try:
        yield
    finally:
        dolfinx.log.set_log_level(previous)


class _CompilerLines(logging.Filter):
    """Route setuptools' log records on the root logger (JIT compiler lines) to ``jit_logger``."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.name != "root" or record.levelno >= logging.WARNING:
            return True
        path = record.pathname.replace("\\", "/")
        if "/distutils/" not in path and "/setuptools/" not in path:
            return True
        jit_logger.debug("%s", record.getMessage())
        return False


def route_compiler_lines() -> None:
    """Install the root-logger filter of :class:`_CompilerLines` (once)."""
    root = logging.getLogger()
    if not any(isinstance(f, _CompilerLines) for f in root.filters):
        root.addFilter(_CompilerLines())
