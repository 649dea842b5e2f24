"""The penetration slope for springs that start an increment at the kink of the LINEAR law.

CalculiX's LINEAR law ``p = K d [1/2 + atan(d/eps)/pi]`` (docs/method.md §4.2) has the slope
``K/2`` at ``d = 0``, where bodies that touch start an increment, and ``K`` a few ``eps`` into
penetration, where they end it. Newton's first step from ``d = 0`` with half the slope overshoots
every such spring, and the increment needs one more iteration (the tie punch of
``benchmarks/ccx_decks.py``: 4 instead of 3). With ``ContactProblem(contact_start_slope=True)``
the first Newton iteration of an attempt takes the slope ``K`` for springs with ``|d| <= eps``;
the residual, and so the converged state, are unchanged (docs/method.md §7.1).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from dolfinx_ntf.kernels.laws import LinearLaw, PressureOverclosureLaw

__all__ = ["PenetrationSlopeAtKink", "start_law"]


class PenetrationSlopeAtKink(PressureOverclosureLaw):
    """A LINEAR law whose derivative is ``K`` within ``eps`` of ``d = 0``; all else delegated."""

    def __init__(self, law: LinearLaw) -> None:
        self.law = law
        self.keyword = law.keyword

    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """The law's pressure."""
        return self.law.pressure(d)

    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """``K`` where ``|d| <= eps``, the law's derivative elsewhere."""
        d_arr = self._d(d)
        kink = np.abs(d_arr) <= self.law.epsilon
        return np.where(kink, self.law.slope, self.law.pressure_derivative(d_arr))

    def cutoff(self, area: npt.ArrayLike) -> np.ndarray:
        """The law's cutoff."""
        return self.law.cutoff(area)

    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """The law's energy."""
        return self.law.energy(d, area)


def start_law(law: PressureOverclosureLaw) -> PressureOverclosureLaw:
    """The law of the first Newton iteration.

    The static LINEAR law with the slope ``K`` at its kink, any other law as it is.
    """
    return PenetrationSlopeAtKink(law) if type(law) is LinearLaw else law
