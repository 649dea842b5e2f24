"""ccx's progress files ``JOB.sta`` and ``JOB.cvg`` (docs/method.md §13.3). Pure Python/numpy.

``JOB.sta`` has one row per attempt: step, increment, attempt (``U`` marks an attempt that did not
converge), Newton iterations, total time, step time and increment size; converged rows give the
times at the end of the increment, failed ones at its start. ``JOB.cvg`` has one row per Newton
iteration: step, increment, attempt, iteration, contact elements, the largest residual force in %
of the mean average force and the largest correction in % of the largest displacement change of
the increment (ccx's convergence quantities, docs/method.md §7.1), then ccx's two thermal columns
(zero). Ratios at round-off level are written as 0 (``roundoff.clean_ratio``, docs/method.md §14.5).
"""

from __future__ import annotations

import math
import typing
from pathlib import Path

from .roundoff import clean_ratio

__all__ = ["CvgFile", "StaFile", "fortran_e"]

_STA_HEADER = (
    "SUMMARY OF JOB INFORMATION\n"
    "  STEP      INC     ATT  ITRS     TOT TIME     STEP TIME      INC TIME\n"
)
_CVG_HEADER = (
    "SUMMARY OF C0NVERGENCE INFORMATION\n"  # sic: ccx 2.20 writes a zero
    "  STEP   INC  ATT   ITER     CONT.   RESID.        CORR.      RESID.      CORR.\n"
    "                              EL.    FORCE         DISP       FLUX        TEMP.\n"
    "                              (#)     (%)           (%)        (%)         (%)\n"
)


def fortran_e(value: float, digits: int) -> str:
    """Fortran's ``E`` edit descriptor: ``0.ddddddE+ee`` (``-0.dd...`` if negative, ``NaN``)."""
    if not math.isfinite(value):
        return f"{'NaN':>{digits + 6}}"
    if value == 0:
        return f"0.{'0' * digits}E+00"
    exponent = math.floor(math.log10(abs(value))) + 1
    mantissa = round(abs(value) / 10.0**exponent, digits)
    if mantissa >= 1.0:
        mantissa /= 10.0
        exponent += 1
    text = f"{mantissa:.{digits}f}"
    return f"{'-' if value < 0 else ''}{text}E{exponent:+03d}"


class StaFile:
    """``JOB.sta``: the header now, one row per attempt."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.write_text(_STA_HEADER)

    def row(
        self,
        step: int,
        increment: int,
        attempt: int,
        converged: bool,
        iterations: int,
        total_time: float,
        step_time: float,
        increment_size: float,
    ) -> None:
        """Append one attempt."""
        times = "".join(f"  {fortran_e(t, 6)}" for t in (total_time, step_time, increment_size))
        flag = " " if converged else "U"
        with self.path.open("a") as stream:
            stream.write(f"{step:6d}{increment:11d}{attempt:6d}{flag}{iterations:5d}{times}\n")


class CvgFile:
    """``JOB.cvg``: the header now, one row per Newton iteration."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.write_text(_CVG_HEADER)

    def rows(
        self,
        step: int,
        increment: int,
        attempt: int,
        history: typing.Sequence[tuple[int, int, float, float, float, float]],
    ) -> None:
        """Append the iterations of one attempt (``ContactNewtonSolver.history``)."""
        lines = []
        for iteration, springs, largest, mean, correction, change in history:
            residual = 100.0 * clean_ratio(largest, mean)
            corrected = 100.0 * clean_ratio(correction, change)
            values = "".join(f"  {fortran_e(v, 4)}" for v in (residual, corrected, 0.0, 0.0))
            lines.append(f"{step:6d}{increment:6d}{attempt:6d}{iteration:6d}{springs:9d}{values}\n")
        with self.path.open("a") as stream:
            stream.writelines(lines)
