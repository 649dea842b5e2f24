"""Pressure-overclosure laws and surface interactions of CalculiX node-to-surface contact.

The laws map the overclosure ``d`` (``d > 0`` is penetration, docs/method.md §3.4) to a contact
pressure ``p(d)`` (positive is compression) and give everything a spring element needs: the spring
force ``F_N = A p(d)`` and its derivative, the pairing cutoff (docs/method.md §3.4) and the spring
energy printed by ``*CONTACT PRINT, CELS`` (docs/method.md §8.3). They reproduce CalculiX 2.20
(docs/method.md §4: ``*SURFACE BEHAVIOR``, ``*FRICTION``), including its quirks, which are listed in
each class docstring.

Shared rules:
    - Every method is vectorized: ``d`` and ``area`` are array-like and broadcast against each
      other; the result is a float ``np.ndarray`` of the broadcast shape.
    - ``area`` is the spring area ``A_p`` of docs/method.md §2.2 and must be ``>= 0``; ``d`` must be
      finite. Bad input raises ``ValueError`` naming the law, the argument and the first bad entry.
    - Pure numpy: no dolfinx import.
"""

from __future__ import annotations

import abc
import math
import sys
import warnings
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt

__all__ = [
    "EXPONENTIAL_FORCE_CAP_EXPONENT",
    "TABULAR_C0",
    "TABULAR_MIN_INCREMENT",
    "ZERO_AREA_CUTOFF",
    "ContactDamping",
    "DynamicLinearLaw",
    "ExponentialLaw",
    "Friction",
    "LinearLaw",
    "PressureOverclosureLaw",
    "SurfaceInteraction",
    "TabularLaw",
]

EXPONENTIAL_FORCE_CAP_EXPONENT: float = 23.0
"""ccx caps the exponential spring force at ``exp(23)`` (absolute force, docs/method.md §4.1)."""

ZERO_AREA_CUTOFF: float = 1e-10
"""Cutoff clearance of LINEAR/TABULAR laws for a node without spring area (docs/method.md §3.4)."""

TABULAR_C0: float = 1e-3
"""Fixed cutoff coefficient of the TABULAR law (docs/method.md §4.3): ``c_cut = 1e-3 sqrt(A)``."""

TABULAR_MIN_INCREMENT: float = 1e-10
"""ccx makes successive tabular overclosures increase by at least this (docs/method.md §4.3)."""

_P0_ZERO: float = 1e-30
_TENSION_MIN: float = 1e-30


def _warn(message: str) -> None:
    """A ``UserWarning`` at the user's call, printed once under MPI (by rank 0 of COMM_WORLD).

    Laws are built alike on every process, so every process would print the same warning; this
    module stays free of MPI and looks at mpi4py only if the program has imported it.
    """
    mpi = sys.modules.get("mpi4py.MPI")
    if mpi is None or mpi.COMM_WORLD.rank == 0:
        warnings.warn(message, UserWarning, stacklevel=3)


def _check_scalar(owner: str, name: str, value: object) -> float:
    """Return ``value`` as a finite float, or raise ``ValueError`` naming owner and parameter."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{owner}: {name} must be a real number, got {value!r}")
    result = float(value)
    if not math.isfinite(result):
        raise ValueError(f"{owner}: {name} must be finite, got {result!r}")
    return result


def _check_array(owner: str, name: str, values: npt.ArrayLike, *, nonnegative: bool) -> np.ndarray:
    """Return ``values`` as a float array; raise ``ValueError`` on non-finite/negative entries."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{owner}: {name} must be numeric, got {values!r}") from err
    bad = ~np.isfinite(array)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(
            f"{owner}: {name} must be finite, got {float(array[index])!r} at index {index}"
        )
    if nonnegative:
        negative = array < 0.0
        if negative.any():
            index = tuple(int(i) for i in np.argwhere(negative)[0])
            raise ValueError(
                f"{owner}: {name} must be >= 0, got {float(array[index])!r} at index {index}"
            )
    return array


class PressureOverclosureLaw(abc.ABC):
    """Base class of the ``*SURFACE BEHAVIOR`` pressure-overclosure laws (docs/method.md §4).

    Subclasses implement :meth:`pressure`, :meth:`pressure_derivative`, :meth:`cutoff` and
    :meth:`energy`; :meth:`spring_force` defaults to ``F_N = A p(d)``.
    """

    keyword: ClassVar[str]
    """The ``PRESSURE-OVERCLOSURE=`` value of the law in a CalculiX deck."""

    def _d(self, d: npt.ArrayLike) -> np.ndarray:
        """Validated overclosures as a float array."""
        return _check_array(type(self).__name__, "overclosure d", d, nonnegative=False)

    def _d_area(self, d: npt.ArrayLike, area: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Validated overclosures and areas, broadcast against each other."""
        owner = type(self).__name__
        d_arr = _check_array(owner, "overclosure d", d, nonnegative=False)
        a_arr = _check_array(owner, "area", area, nonnegative=True)
        try:
            d_b, a_b = np.broadcast_arrays(d_arr, a_arr)
        except ValueError as err:
            raise ValueError(
                f"{owner}: overclosure d of shape {d_arr.shape} and area of shape {a_arr.shape} "
                "do not broadcast"
            ) from err
        return d_b, a_b

    @abc.abstractmethod
    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """Contact pressure ``p(d)`` (compression positive) at overclosures ``d``."""

    @abc.abstractmethod
    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """Derivative ``dp/dd`` at overclosures ``d``."""

    def spring_force(self, d: npt.ArrayLike, area: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Normal spring force ``F_N = A p(d)`` and ``dF_N/dd`` (docs/method.md §5).

        Args:
            d: Overclosures ``d = -g_eff``.
            area: Spring areas ``A_p`` (``>= 0``), constant in the linearization
                (docs/method.md §6.3).

        Returns:
            ``(F_N, dF_N/dd)``, both of the broadcast shape.
        """
        d_b, a_b = self._d_area(d, area)
        return a_b * self.pressure(d_b), a_b * self.pressure_derivative(d_b)

    @abc.abstractmethod
    def cutoff(self, area: npt.ArrayLike) -> np.ndarray:
        """Cutoff ``c_cut``: a spring is created iff ``g_eff <= c_cut`` (docs/method.md §3.4).

        ``area`` is the slave node's spring area ``A``, one per node.
        """

    @abc.abstractmethod
    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """Spring energy of ``*CONTACT PRINT, CELS`` without friction (docs/method.md §8.3).

        ``d`` is the overclosure (positive = penetration), ``area`` the spring area ``A``.
        """


class ExponentialLaw(PressureOverclosureLaw):
    """``PRESSURE-OVERCLOSURE=EXPONENTIAL``: ``p = p0 exp(beta d)``, ``beta = ln(100)/c0``.

    ``c0`` is the clearance at which the pressure has dropped to 1% of ``p0``; it is also the
    (absolute) pairing cutoff.

    ccx quirks reproduced:
        - **Force cap** (:meth:`spring_force`): ccx evaluates ``F_N = exp(beta d + ln(A p0))``.
          Where the exponent exceeds 23 it replaces ``beta`` for that evaluation by
          ``beta' = (ln(A p0) - 23)/g`` with ``g = -d``, so ``F_N = exp(23)`` (an *absolute* force,
          about 9.745e9, whatever the units) and the returned derivative is ``beta' F_N``, not 0.
          At ``g == 0`` (only possible when ``A p0 > exp(23)``) ccx would divide by zero; we return
          ``beta F_N`` there instead.
        - ``p0 < 1e-30`` gives zero force, zero pressure and zero energy.

    :meth:`pressure` and :meth:`pressure_derivative` are the uncapped law (they overflow to
    ``inf`` for huge ``beta d``); only spring forces and energies are capped.
    """

    keyword: ClassVar[str] = "EXPONENTIAL"

    def __init__(self, c0: float, p0: float) -> None:
        """Create the law from the ``*SURFACE BEHAVIOR`` data line ``c0, p0``.

        Args:
            c0: Clearance ``> 0`` at which ``p = p0/100`` [length].
            p0: Pressure at zero clearance ``>= 0`` [force/length^2].
        """
        owner = "ExponentialLaw"
        self.c0 = _check_scalar(owner, "c0", c0)
        self.p0 = _check_scalar(owner, "p0", p0)
        if self.c0 <= 0.0:
            raise ValueError(f"{owner}: c0 must be > 0, got {self.c0!r}")
        if self.p0 < 0.0:
            raise ValueError(f"{owner}: p0 must be >= 0, got {self.p0!r}")
        self.beta = math.log(100.0) / self.c0

    def __repr__(self) -> str:
        """Constructor-like representation."""
        return f"ExponentialLaw(c0={self.c0!r}, p0={self.p0!r})"

    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """Uncapped ``p0 exp(beta d)`` (0 if ``p0 < 1e-30``)."""
        d_arr = self._d(d)
        if self.p0 < _P0_ZERO:
            return np.zeros_like(d_arr)
        with np.errstate(over="ignore"):
            return self.p0 * np.exp(self.beta * d_arr)

    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """Uncapped ``beta p(d)``."""
        return self.beta * self.pressure(d)

    def spring_force(self, d: npt.ArrayLike, area: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """``F_N = A p(d)`` with ccx's ``exp(23)`` cap, and ``dF_N/dd`` as ccx computes it.

        See the class docstring for the cap. Zero area or ``p0 < 1e-30`` gives zero force.
        """
        d_b, a_b = self._d_area(d, area)
        force = np.zeros(d_b.shape)
        dforce = np.zeros(d_b.shape)
        if self.p0 < _P0_ZERO:
            return force, dforce
        live = a_b > 0.0
        d_l = d_b[live]
        log_ap0 = np.log(a_b[live]) + math.log(self.p0)
        exponent = self.beta * d_l + log_ap0
        capped = exponent > EXPONENTIAL_FORCE_CAP_EXPONENT
        f_l = np.exp(np.minimum(exponent, EXPONENTIAL_FORCE_CAP_EXPONENT))
        slope = np.full(d_l.shape, self.beta)
        gap = -d_l[capped]
        nonzero_gap = gap != 0.0
        beta_cap = np.full(gap.shape, self.beta)
        beta_cap[nonzero_gap] = (
            log_ap0[capped][nonzero_gap] - EXPONENTIAL_FORCE_CAP_EXPONENT
        ) / gap[nonzero_gap]
        slope[capped] = beta_cap
        force[live] = f_l
        dforce[live] = slope * f_l
        return force, dforce

    def cutoff(self, area: npt.ArrayLike) -> np.ndarray:
        """``c0``, independent of the area (docs/method.md §3.4)."""
        a_arr = _check_array("ExponentialLaw", "area", area, nonnegative=True)
        return np.full(a_arr.shape, self.c0)

    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """``F_N/beta`` with the capped force (docs/method.md §8.3).

        ``d`` is the overclosure, ``area`` the spring area ``A``.
        """
        force, _ = self.spring_force(d, area)
        return force / self.beta


class LinearLaw(PressureOverclosureLaw):
    """``PRESSURE-OVERCLOSURE=LINEAR`` (and ``HARD``), static form (docs/method.md §4.2).

    ``p(d) = K d [1/2 + atan(d/eps)/pi]`` with ``eps = pi sigma_inf/K``: a smoothed penalty spring
    of slope ``K`` in penetration that tends to the tension ``-sigma_inf`` for ``d -> -inf``.
    The pairing cutoff is ``c0 sqrt(A)`` (``1e-10`` where ``A == 0``). The energy is ccx 2.20's
    approximation ``F_N d/2``, not the integral. The ``*DYNAMIC`` variant (no tension) is
    :class:`DynamicLinearLaw` (:meth:`dynamic`).
    """

    keyword: ClassVar[str] = "LINEAR"

    def __init__(self, slope: float, tension: float, c0: float = 1e-3) -> None:
        """Create the law from explicit values (no ccx defaults, see :meth:`with_ccx_defaults`).

        Args:
            slope: Penalty slope ``K > 0`` [force/length^3].
            tension: Limit tension ``sigma_inf >= 1e-30`` [force/length^2]; ccx rejects smaller
                values for node-to-surface contact.
            c0: Dimensionless cutoff coefficient ``> 0``.
        """
        owner = "LinearLaw"
        self.slope = _check_scalar(owner, "slope", slope)
        self.tension = _check_scalar(owner, "tension", tension)
        self.c0 = _check_scalar(owner, "c0", c0)
        if self.slope <= 0.0:
            raise ValueError(f"{owner}: slope must be > 0, got {self.slope!r}")
        if self.tension < _TENSION_MIN:
            raise ValueError(
                f"{owner}: tension must be >= {_TENSION_MIN} for node-to-surface contact, "
                f"got {self.tension!r}"
            )
        if self.c0 <= 0.0:
            raise ValueError(f"{owner}: c0 must be > 0, got {self.c0!r}")
        self.epsilon = math.pi * self.tension / self.slope

    @classmethod
    def with_ccx_defaults(
        cls,
        youngs_modulus: float,
        slope: float | None = None,
        tension: float | None = None,
        c0: float | None = None,
    ) -> LinearLaw:
        """Create the law as ccx reads ``*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR|HARD``.

        Missing or non-positive values get ccx's defaults (docs/method.md §4.2): ``K = 50 E``,
        ``sigma_inf = E/70000``, ``c0 = 1e-3``. Zero asks for the default as in a deck; a
        negative value is replaced too, as ccx does, but with a ``UserWarning`` naming it (ccx
        replaces it silently).

        Args:
            youngs_modulus: ``E``, the first constant of material no. 1 (``> 0``).
            slope: ``K`` or ``None``.
            tension: ``sigma_inf`` or ``None``.
            c0: Cutoff coefficient or ``None``.
        """
        owner = "LinearLaw.with_ccx_defaults"
        e = _check_scalar(owner, "youngs_modulus", youngs_modulus)
        if e <= 0.0:
            raise ValueError(f"{owner}: youngs_modulus must be > 0, got {e!r}")
        defaults = {"slope": 50.0 * e, "tension": e / 70000.0, "c0": 1e-3}
        rules = {"slope": "50 E", "tension": "E/70000", "c0": "1e-3"}
        values = {}
        for name, value in (("slope", slope), ("tension", tension), ("c0", c0)):
            given = None if value is None else _check_scalar(owner, name, value)
            if given is not None and given < 0.0:
                _warn(
                    f"{owner}: {name} = {given!r} is negative; using ccx's default "
                    f"{rules[name]} = {defaults[name]!r} instead (pass None to ask for it)"
                )
            values[name] = defaults[name] if given is None or given <= 0.0 else given
        return cls(**values)

    def __repr__(self) -> str:
        """Constructor-like representation."""
        return f"LinearLaw(slope={self.slope!r}, tension={self.tension!r}, c0={self.c0!r})"

    def dynamic(self) -> DynamicLinearLaw:
        """The same law as CalculiX applies it in ``*DYNAMIC`` steps (no tension)."""
        return DynamicLinearLaw(self.slope, self.tension, self.c0)

    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """``K d [1/2 + atan(d/eps)/pi]``."""
        d_arr = self._d(d)
        return self.slope * d_arr * (0.5 + np.arctan(d_arr / self.epsilon) / math.pi)

    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """``K [1/2 + atan(x)/pi + x/(pi (1 + x^2))]``, ``x = d/eps``."""
        x = self._d(d) / self.epsilon
        with np.errstate(over="ignore"):
            rational = x / (1.0 + x * x)
        return self.slope * (0.5 + (np.arctan(x) + rational) / math.pi)

    def cutoff(self, area: npt.ArrayLike) -> np.ndarray:
        """``c0 sqrt(A)``, or ``1e-10`` where ``A == 0`` (docs/method.md §3.4).

        ``area`` is the slave node's spring area ``A``, one per node.
        """
        a_arr = _check_array("LinearLaw", "area", area, nonnegative=True)
        return np.where(a_arr > 0.0, self.c0 * np.sqrt(a_arr), ZERO_AREA_CUTOFF)

    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """ccx 2.20's static approximation ``F_N d/2`` at overclosure ``d``, spring ``area`` A."""
        d_b, a_b = self._d_area(d, area)
        force, _ = self.spring_force(d_b, a_b)
        return 0.5 * force * d_b


class DynamicLinearLaw(LinearLaw):
    """The LINEAR law as CalculiX applies it in ``*DYNAMIC`` steps (docs/method.md §4.2, §12.3).

    The static pressure for ``d >= 0`` and **no tension** for ``d < 0``; the derivative is exact
    (zero in tension; ccx keeps the full formula's [inferred], which changes iterations only). The
    energy is the exact integral ``A int_0^d p``, so that the spring is conservative and enters
    an energy balance. ``LinearLaw.dynamic()`` makes one from a static law.
    """

    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """``K d [1/2 + atan(d/eps)/pi]`` for ``d >= 0``, 0 otherwise."""
        d_arr = self._d(d)
        return np.where(d_arr > 0.0, super().pressure(np.maximum(d_arr, 0.0)), 0.0)

    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """The static slope for ``d > 0``, 0 otherwise."""
        d_arr = self._d(d)
        return np.where(d_arr > 0.0, super().pressure_derivative(np.maximum(d_arr, 0.0)), 0.0)

    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """``A K [d^2/4 + ((d^2 + eps^2) atan(d/eps) - eps d) / (2 pi)]`` for ``d > 0``, else 0.

        ``d`` is the overclosure, ``area`` the spring area ``A``.
        """
        d_b, a_b = self._d_area(d, area)
        dp = np.maximum(d_b, 0.0)
        eps = self.epsilon
        integral = dp * dp / 4.0 + ((dp * dp + eps * eps) * np.arctan(dp / eps) - eps * dp) / (
            2.0 * math.pi
        )
        return a_b * self.slope * integral

    def __repr__(self) -> str:
        """Constructor-like representation."""
        return f"DynamicLinearLaw(slope={self.slope!r}, tension={self.tension!r}, c0={self.c0!r})"


class TabularLaw(PressureOverclosureLaw):
    """``PRESSURE-OVERCLOSURE=TABULAR``: piecewise-linear ``p(d)`` through the table points.

    Outside the table the pressure is constant (``p_1`` below ``d_1``, ``p_N`` above ``d_N``) with
    zero slope. At an interior table point :meth:`pressure_derivative` returns the slope of the
    segment to the right; at ``d_N`` it returns 0. The pairing cutoff is ``1e-3 sqrt(A)``
    (``1e-10`` where ``A == 0``); ``c0`` is fixed.

    Choices and ccx quirks:
        - Overclosures must not decrease (``ValueError`` naming the index). Successive values
          closer than ``1e-10`` (including equal ones) are pushed apart to exactly ``1e-10`` as
          ccx does (docs/method.md §4.3); the nudged values are in ``overclosures``.
        - At least 2 points are required. Negative pressures are allowed (CalculiX says nothing
          about them).
        - ccx resamples tables longer than 200 points to 200; its rule is not documented, so
          all points are kept.
        - Temperature-dependent tables are not supported.
        - Energy (docs/method.md §8.3): ``A`` times the trapezoidal integral of ``p`` from ``d_1``
          to ``d``. Beyond ``d_N`` (strictly) ccx adds ``(p_N - d_N) p_N`` to the full-table
          integral instead of ``(d - d_N) p_N``; this quirk is reproduced. Below ``d_1`` we return
          ``A p_1 (d - d_1)`` (the integral of the constant extrapolation; not verified against
          ccx).
    """

    keyword: ClassVar[str] = "TABULAR"

    def __init__(self, pressures: npt.ArrayLike, overclosures: npt.ArrayLike) -> None:
        """Create the law from the data lines ``pressure, overclosure``.

        Args:
            pressures: ``p_i`` [force/length^2], one per table point.
            overclosures: ``d_i`` [length], non-decreasing.
        """
        owner = "TabularLaw"
        p = _check_array(owner, "pressures", pressures, nonnegative=False)
        d = _check_array(owner, "overclosures", overclosures, nonnegative=False)
        if p.ndim != 1 or d.ndim != 1:
            raise ValueError(
                f"{owner}: pressures and overclosures must be 1-D, got shapes {p.shape} and "
                f"{d.shape}"
            )
        if p.shape != d.shape:
            raise ValueError(
                f"{owner}: {p.size} pressures but {d.size} overclosures; they must match"
            )
        if p.size < 2:
            raise ValueError(f"{owner}: at least 2 table points are required, got {p.size}")
        decreasing = np.flatnonzero(np.diff(d) < 0.0)
        if decreasing.size:
            i = int(decreasing[0]) + 1
            raise ValueError(
                f"{owner}: overclosures must increase, but point {i} ({d[i]!r}) is below point "
                f"{i - 1} ({d[i - 1]!r})"
            )
        d = d.copy()
        for i in range(1, d.size):  # loop over table points only
            if d[i] - d[i - 1] < TABULAR_MIN_INCREMENT:
                d[i] = d[i - 1] + TABULAR_MIN_INCREMENT
        p = p.copy()
        p.setflags(write=False)
        d.setflags(write=False)
        self.pressures = p
        self.overclosures = d
        self.c0 = TABULAR_C0
        self._slopes = np.diff(p) / np.diff(d)
        trapezoids = 0.5 * (p[1:] + p[:-1]) * np.diff(d)
        self._integral = np.concatenate(([0.0], np.cumsum(trapezoids)))

    def __repr__(self) -> str:
        """Constructor-like representation."""
        return (
            f"TabularLaw(pressures={self.pressures.tolist()!r}, "
            f"overclosures={self.overclosures.tolist()!r})"
        )

    def _segment(self, d_arr: np.ndarray) -> np.ndarray:
        """Index k of the segment [d_k, d_k+1) holding each d; -1 below, N-1 at or above d_N."""
        return np.searchsorted(self.overclosures, d_arr, side="right") - 1

    def pressure(self, d: npt.ArrayLike) -> np.ndarray:
        """Pressure at overclosure ``d``: piecewise-linear interpolation, constant extrapolation."""
        d_arr = self._d(d)
        return np.interp(d_arr, self.overclosures, self.pressures)

    def pressure_derivative(self, d: npt.ArrayLike) -> np.ndarray:
        """Slope at overclosure ``d`` (right segment at table points), 0 outside ``[d_1, d_N)``."""
        d_arr = self._d(d)
        k = self._segment(d_arr)
        inside = (k >= 0) & (k < self._slopes.size)
        return np.where(inside, self._slopes[np.clip(k, 0, self._slopes.size - 1)], 0.0)

    def cutoff(self, area: npt.ArrayLike) -> np.ndarray:
        """``1e-3 sqrt(A)``, or ``1e-10`` where ``A == 0`` (docs/method.md §3.4).

        ``area`` is the slave node's spring area ``A``, one per node.
        """
        a_arr = _check_array("TabularLaw", "area", area, nonnegative=True)
        return np.where(a_arr > 0.0, TABULAR_C0 * np.sqrt(a_arr), ZERO_AREA_CUTOFF)

    def energy(self, d: npt.ArrayLike, area: npt.ArrayLike) -> np.ndarray:
        """``A`` times the trapezoidal integral of ``p`` from ``d_1``, ccx quirk beyond ``d_N``.

        ``d`` is the overclosure, ``area`` the spring area ``A``.
        """
        d_b, a_b = self._d_area(d, area)
        p_tab, d_tab = self.pressures, self.overclosures
        last = d_tab.size - 1
        k = self._segment(d_b)
        k_in = np.clip(k, 0, last)
        inside = self._integral[k_in] + 0.5 * (d_b - d_tab[k_in]) * (
            p_tab[k_in] + np.interp(d_b, d_tab, p_tab)
        )
        beyond = self._integral[last] + (p_tab[last] - d_tab[last]) * p_tab[last]
        below = p_tab[0] * (d_b - d_tab[0])
        work = np.where(k < 0, below, np.where(d_b > d_tab[last], beyond, inside))
        return a_b * work


@dataclass(frozen=True)
class ContactDamping:
    """``*CONTACT DAMPING`` data: damping constant ``c`` and tangent fraction ``f``.

    Used as ``SurfaceInteraction(law, damping=ContactDamping(c, f))``. In dynamic steps every
    contact spring then adds the force ``c A [(v_rel.n) n + f (v_rel - (v_rel.n) n)]`` on its
    slave node (the master face gets the opposite force through the projection weights), ``A``
    the spring area and ``v_rel`` the slave node's velocity relative to the master point
    (docs/method.md §29). Static steps ignore it, as CalculiX does.

    Attributes:
        coefficient: ``c > 0`` [force time/length^3]: a dashpot of ``c A`` per spring, normally.
        tangent_fraction: ``f >= 0`` (default 0: normal damping only); the tangential dashpot is
            ``f c A``.
    """

    coefficient: float
    tangent_fraction: float = 0.0

    def __post_init__(self) -> None:
        """Validate the parameters."""
        owner = "ContactDamping"
        coefficient = _check_scalar(owner, "coefficient", self.coefficient)
        fraction = _check_scalar(owner, "tangent_fraction", self.tangent_fraction)
        if coefficient <= 0.0:
            raise ValueError(f"{owner}: coefficient must be > 0, got {coefficient!r}")
        if fraction < 0.0:
            raise ValueError(f"{owner}: tangent_fraction must be >= 0, got {fraction!r}")
        object.__setattr__(self, "coefficient", coefficient)
        object.__setattr__(self, "tangent_fraction", fraction)


@dataclass(frozen=True)
class Friction:
    """``*FRICTION`` data: Coulomb coefficient ``mu`` and stick slope ``lambda``.

    Used as ``SurfaceInteraction(law, Friction(mu, stick_slope))`` (docs/method.md §4.5, §11).

    Attributes:
        mu: Friction coefficient, ``> 0`` (ccx rejects ``mu <= 0``).
        stick_slope: Tangential penalty ``lambda > 0`` [force/length^3]; ``K_t = lambda A_p``.
    """

    mu: float
    stick_slope: float

    def __post_init__(self) -> None:
        """Validate the parameters."""
        owner = "Friction"
        mu = _check_scalar(owner, "mu", self.mu)
        stick_slope = _check_scalar(owner, "stick_slope", self.stick_slope)
        if mu <= 0.0:
            raise ValueError(f"{owner}: mu must be > 0, got {mu!r}")
        if stick_slope <= 0.0:
            raise ValueError(f"{owner}: stick_slope must be > 0, got {stick_slope!r}")
        object.__setattr__(self, "mu", mu)
        object.__setattr__(self, "stick_slope", stick_slope)

    @classmethod
    def with_ccx_defaults(
        cls, mu: float, stick_slope: float | None, youngs_modulus: float
    ) -> Friction:
        """Create friction data as ccx reads ``*FRICTION``: ``lambda <= 0`` or missing -> ``E/2``.

        Like ccx, the default is announced with a warning (``UserWarning``).

        Args:
            mu: Friction coefficient ``> 0``.
            stick_slope: ``lambda`` or ``None``.
            youngs_modulus: ``E``, the first constant of material no. 1 (``> 0``).
        """
        owner = "Friction.with_ccx_defaults"
        e = _check_scalar(owner, "youngs_modulus", youngs_modulus)
        if e <= 0.0:
            raise ValueError(f"{owner}: youngs_modulus must be > 0, got {e!r}")
        lam = None if stick_slope is None else _check_scalar(owner, "stick_slope", stick_slope)
        if lam is None or lam <= 0.0:
            _warn(
                f"*FRICTION: stick slope {lam!r} is missing or not positive; "
                f"using E/2 = {e / 2.0!r}"
            )
            lam = 0.5 * e
        return cls(mu=mu, stick_slope=lam)


@dataclass(frozen=True)
class SurfaceInteraction:
    """``*SURFACE INTERACTION``: a pressure-overclosure law, optional friction and damping.

    Attributes:
        law: The ``*SURFACE BEHAVIOR`` law.
        friction: The ``*FRICTION`` data, or ``None`` for frictionless contact.
        damping: The ``*CONTACT DAMPING`` data (acts in dynamic steps only), or ``None``.
    """

    law: PressureOverclosureLaw
    friction: Friction | None = None
    damping: ContactDamping | None = None

    def __post_init__(self) -> None:
        """Check the types, so that a deck-reader mistake fails here and not in the solver."""
        if not isinstance(self.law, PressureOverclosureLaw):
            raise ValueError(
                f"SurfaceInteraction: law must be a PressureOverclosureLaw, got {self.law!r}"
            )
        if self.friction is not None and not isinstance(self.friction, Friction):
            raise ValueError(
                f"SurfaceInteraction: friction must be a Friction or None, got {self.friction!r}"
            )
        if self.damping is not None and not isinstance(self.damping, ContactDamping):
            raise ValueError(
                "SurfaceInteraction: damping must be a ContactDamping or None, got "
                f"{self.damping!r}"
            )
