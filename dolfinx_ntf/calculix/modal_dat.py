"""The ``.dat`` blocks of a ``*FREQUENCY`` step as ccx 2.20 writes them (docs/method.md §16).

Eigenvalues with their frequencies, participation factors, effective modal masses with their
totals, and the total effective mass; rows ``I7`` then ``E16.7`` values (Fortran's ``0.dddE+xx``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

__all__ = ["FrequencyTables", "format_e16", "frequency_output", "read_frequency_output"]

_COMPONENTS = (
    "MODE NO.   X-COMPONENT     Y-COMPONENT     Z-COMPONENT     X-ROTATION      Y-ROTATION"
    "      Z-ROTATION\n"
)


def format_e16(value: float) -> str:
    """Fortran ``E16.7`` (``   0.1310219E+05``): mantissa in [0.1, 1), right-aligned in 16."""
    value = float(value)
    if value == 0.0 or not math.isfinite(value):
        return "   0.0000000E+00" if value == 0.0 else f"{value:>16}"
    exponent = math.floor(math.log10(abs(value))) + 1
    mantissa = value / 10.0**exponent
    text = f"{mantissa:.7f}"
    if abs(float(text)) >= 1.0:  # rounding reached 1.0000000
        exponent += 1
        text = f"{value / 10.0**exponent:.7f}"
    sign = "-" if text.startswith("-") else ""
    return f"{sign}{text.lstrip('-')}E{exponent:+03d}".rjust(16)


def _rows(labels: list[str], values: np.ndarray) -> str:
    return "".join(
        label + "".join(format_e16(v) for v in row) + "\n" for label, row in zip(labels, values)
    )


def frequency_output(
    eigenvalues: np.ndarray, participation: np.ndarray, total_mass: np.ndarray
) -> str:
    """The text of ccx 2.20's frequency-step blocks, blank line first.

    Args:
        eigenvalues: ``omega^2`` of the modes, ascending.
        participation: Participation factors, shape (modes, 6).
        total_mass: ``r_k^T M r_k`` of the six rigid motions (the total effective mass).
    """
    eigenvalues = np.asarray(eigenvalues, dtype=float)
    omega = np.sqrt(np.abs(eigenvalues))
    table = np.column_stack([eigenvalues, omega, omega / (2 * math.pi), np.zeros_like(omega)])
    labels = [f"{k:7d}" for k in range(1, eigenvalues.size + 1)]
    effective = np.asarray(participation) ** 2
    return (
        "\n     E I G E N V A L U E   O U T P U T\n\n"
        " MODE NO    EIGENVALUE                       FREQUENCY   \n"
        "                                     REAL PART            IMAGINARY PART\n"
        "                           (RAD/TIME)      (CYCLES/TIME     (RAD/TIME)\n\n"
        + _rows(labels, table)
        + "\n     P A R T I C I P A T I O N   F A C T O R S\n\n"
        + _COMPONENTS
        + "\n"
        + _rows(labels, participation)
        + "\n     E F F E C T I V E   M O D A L   M A S S\n\n"
        + _COMPONENTS
        + "\n"
        + _rows(labels, effective)
        + _rows(["TOTAL  "], effective.sum(axis=0, keepdims=True))
        + "\n     T O T A L   E F F E C T I V E   M A S S\n\n"
        + _COMPONENTS
        + "\n"
        + _rows(["       "], np.asarray(total_mass, dtype=float).reshape(1, 6))
        + "\n\n"
    )


@dataclasses.dataclass
class FrequencyTables:
    """The tables of a frequency step read back from a ``.dat`` text (mode numbers dropped).

    Attributes:
        eigenvalues: (modes, 4): eigenvalue, rad/time, cycles/time, imaginary part.
        participation: (modes, 6) participation factors.
        effective_mass: (modes, 6) effective modal masses.
        total_text: The total effective mass row as printed.
    """

    eigenvalues: np.ndarray
    participation: np.ndarray
    effective_mass: np.ndarray
    total_text: str


def read_frequency_output(text: str) -> FrequencyTables:
    """The first frequency step's tables of the ``.dat`` ``text`` (ccx's or ours).

    Args:
        text: The ``.dat`` file's content.
    """
    lines = text.splitlines()

    def table(title: str) -> np.ndarray:
        start = next(i for i, line in enumerate(lines) if title in line)
        rows = []
        for line in lines[start + 1 :]:
            fields = line.split()
            if fields and fields[0].isdigit():
                rows.append([float(f) for f in fields[1:]])
            elif rows:
                break
        return np.array(rows)

    total = "T O T A L   E F F E C T I V E   M A S S"
    start = next(i for i, line in enumerate(lines) if total in line)
    return FrequencyTables(
        table("E I G E N V A L U E   O U T P U T"),
        table("P A R T I C I P A T I O N   F A C T O R S"),
        table("E F F E C T I V E   M O D A L   M A S S"),
        next(line for line in lines[start + 1 :] if line.strip() and line[0] == " "),
    )
