"""Values below their accuracy written as zero in the deck runner's files (docs/method.md §14.5).

ccx prints every value with 7 (``.dat``) or 6 (``.frd``) significant digits, whatever its size,
so a quantity that is zero in exact arithmetic (a shear stress zero by symmetry, the force at a
free node) is printed as its round-off, e.g. ``-3.116438E-17``. That round-off comes from the
linear solver and the assembly, whose rounding depends on how the mesh is distributed over the
processes, so the same deck would print other digits on another number of processes. Three
rules, applied in serial and in parallel alike, write such values as 0:

- any printed value of magnitude at most :data:`ROUND_OFF` times the largest magnitude of its
  block (of its column for contact blocks: clearance, slips, pressure and shears apart);
- a nodal force ``RF`` component of magnitude at most the largest residual force ``r`` of the
  converged Newton iterate (plus the first rule's bound): at a free node ``RF`` *is* the residual
  the Newton iteration accepted, and every reaction is known only to within ``r``; a total
  ``RF`` over ``n`` nodes is known to within ``n`` times that;
- a stress or a contact value within the round-off of the displacement it is computed from
  (:class:`FieldAccuracy`). A block whose values are all round-off (the stresses of a body in
  free flight) has round-off as its largest, and the first rule cannot clear it. The
  displacement ``u`` and the coordinates are taken as known to :data:`FIELD_ROUND_OFF` of their
  largest magnitudes ``U`` and ``L``, carried through each formula: a stress (a modulus times
  displacement differences over an element) to ``FIELD_ROUND_OFF M U / h`` (``M`` the largest
  ``lambda + 2 mu``, ``h`` the smallest distance between two nodes of an element); a nodal force
  ``RF`` (a stress times a shape function gradient, about ``1/h``, over the volume of the
  elements at the node) to that times ``d^2`` (``d`` the largest distance between two nodes of
  an element), added to the second rule's bound; a clearance
  or a slip (a difference of current positions) to ``FIELD_ROUND_OFF (L + U)``; a contact
  pressure and a spring energy to what the pair's law changes over that clearance accuracy
  (:func:`law_accuracy`).

The ``.cvg`` ratios (residual per mean force, correction per displacement change) follow the
first rule with their scale as the block's largest.
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np

from dolfinx_ntf.kernels.laws import PressureOverclosureLaw

from .dat import DatBlock
from .frd import FrdBlock

if typing.TYPE_CHECKING:
    from .output_values import ContactRows

__all__ = [
    "FIELD_ROUND_OFF",
    "ROUND_OFF",
    "FieldAccuracy",
    "clean",
    "clean_contact",
    "clean_dat_blocks",
    "clean_frd_block",
    "clean_ratio",
    "clean_totals",
    "element_sizes",
    "force_floor",
    "largest_modulus",
    "law_accuracy",
    "zero_below",
]

_Block = typing.TypeVar("_Block", DatBlock, FrdBlock)

#: A printed value at most this fraction of its block's largest magnitude is written as 0: below
#: the last printed digit of the block's largest value (5e-7 of it, 7 digits). Partition
#: round-off measured: at most 1.4e-13 (dolfinx 0.5) and 7.5e-12 (0.9) of it; a zero-by-symmetry
#: shear stress of the converged iterate: 2.4e-9 of it (docs/method.md §14.5).
ROUND_OFF: float = 1e-7

#: The displacement and the coordinates are known to this fraction of their largest magnitudes:
#: 4500 times the machine epsilon (2.2e-16), a margin for the linear solve's error growth. The
#: stresses of a body in free flight measured: 2.2e-16 of ``M U / h`` (docs/method.md §14.5).
FIELD_ROUND_OFF: float = 1e-12

#: Column groups cleaned apart: the contact quantities (clearance, slips, pressure, shears) are
#: separate fields, each column its own (ccx's are compared column by column).
_GROUPS: dict[str, tuple[list[int], ...]] = {
    "CONTACT": ([0], [1], [2], [3], [4], [5]),
    "CDIS": ([0], [1], [2]),
    "CSTR": ([0], [1], [2]),
}


def clean(values: np.ndarray, floor: float = 0.0) -> np.ndarray:
    """A copy of ``values`` with its round-off set to 0.

    Entries of magnitude at most ``max(floor, ROUND_OFF * largest finite magnitude)`` become 0;
    non-finite entries are kept.
    """
    values = np.array(values, dtype=np.float64)
    magnitude = np.abs(values)
    finite = np.isfinite(magnitude)
    largest = float(magnitude[finite].max(initial=0.0))
    values[finite & (magnitude <= max(floor, ROUND_OFF * largest))] = 0.0
    return values


def force_floor(forces: np.ndarray, residual: float) -> float:
    """The accuracy of a nodal force ``RF``.

    ``residual`` (the largest residual force of the converged iterate) plus ``ROUND_OFF`` times
    the largest force.
    """
    finite = np.abs(np.asarray(forces, dtype=np.float64))
    finite = finite[np.isfinite(finite)]
    return residual + ROUND_OFF * float(finite.max(initial=0.0))


def clean_totals(blocks: list[DatBlock], count: int, floor: float) -> list[DatBlock]:
    """``RF_TOTAL`` blocks cleaned with the sum of their terms' accuracies as floor.

    A total over ``count`` nodes is known to ``count * floor`` (:func:`force_floor`); other blocks
    are unchanged.
    """
    return [
        dataclasses.replace(b, values=clean(b.values, count * floor)) if b.name == "RF_TOTAL" else b
        for b in blocks
    ]


def clean_ratio(value: float, scale: float) -> float:
    """``value / scale``, or 0 at round-off level.

    ``.cvg``: residual per mean force, correction per displacement change. 0 when ``|value|`` is
    at most ``ROUND_OFF * scale`` or ``scale`` is not positive.
    """
    if not scale > 0.0 or abs(value) <= ROUND_OFF * scale:
        return 0.0
    return value / scale


def clean_dat_blocks(blocks: list[DatBlock]) -> list[DatBlock]:
    """``.dat`` blocks with :func:`clean` applied to each (``CNUM`` counts untouched)."""
    return [block if block.name == "CNUM" else _clean_groups(block) for block in blocks]


def _clean_groups(block: _Block) -> _Block:
    """A block (``DatBlock`` or ``FrdBlock``) with :func:`clean` applied per column group."""
    values = np.array(block.values, dtype=np.float64)
    if values.ndim != 2 or values.size == 0:  # nothing to clean (e.g. no contact element)
        return block
    for columns in _GROUPS.get(block.name, (list(range(values.shape[1])),)):
        values[:, columns] = clean(values[:, columns])
    return dataclasses.replace(block, values=values)


def clean_frd_block(block: FrdBlock) -> FrdBlock:
    """An ``.frd`` result block with :func:`clean` applied to each column group."""
    return _clean_groups(block)


@dataclasses.dataclass(frozen=True)
class FieldAccuracy:
    """Accuracy of the values computed from the displacement at one time (docs/method.md §14.5).

    Attributes:
        length: Of a clearance or a slip: ``FIELD_ROUND_OFF (L + U)``.
        stress: Of a stress: ``FIELD_ROUND_OFF M U / h``.
        force: Of a nodal force: ``stress d^2``.
        strain: Of a strain: ``FIELD_ROUND_OFF U / h``.
    """

    length: float
    stress: float
    force: float
    strain: float = 0.0

    @property
    def energy(self) -> float:
        """Of a strain energy density: ``FIELD_ROUND_OFF M (U / h)^2``."""
        return self.stress * self.strain / FIELD_ROUND_OFF

    @classmethod
    def of(
        cls,
        coordinates: float,
        displacement: float,
        modulus: float,
        sizes: tuple[float, float],
    ) -> FieldAccuracy:
        """The accuracy of the values of a displacement field.

        From the largest coordinate ``L`` and displacement ``U`` magnitudes, the largest modulus
        ``M`` and the element sizes ``(h, d)`` of :func:`element_sizes` (no stress or force
        bound when ``h`` is 0).
        """
        smallest, largest = sizes
        length = FIELD_ROUND_OFF * (coordinates + displacement)
        strain = FIELD_ROUND_OFF * displacement / smallest if smallest > 0.0 else 0.0
        return cls(length, modulus * strain, modulus * strain * largest**2, strain)


def law_accuracy(
    law: PressureOverclosureLaw, overclosure: np.ndarray, area: np.ndarray, length: float
) -> tuple[np.ndarray, np.ndarray]:
    """Accuracy of each spring's pressure and energy (``law``: a ``PressureOverclosureLaw``).

    The largest change of ``law.pressure`` and ``law.energy`` when the overclosure moves by
    ``length`` (the clearance's accuracy) either way.
    """
    d = np.asarray(overclosure, dtype=np.float64)
    area = np.asarray(area, dtype=np.float64)
    pressure, energy = law.pressure(d), law.energy(d, area)
    dp, de = np.zeros_like(d), np.zeros_like(d)
    for shifted in (d - length, d + length):
        dp = np.maximum(dp, np.abs(law.pressure(shifted) - pressure))
        de = np.maximum(de, np.abs(law.energy(shifted, area) - energy))
    return dp, de


def zero_below(values: np.ndarray, floor: float | np.ndarray) -> np.ndarray:
    """A copy of ``values`` with the entries of magnitude at most ``floor`` set to 0.

    ``floor``: a scalar, or one per row (first axis). Unlike :func:`clean`, no block rule.
    """
    values = np.array(values, dtype=np.float64)
    floor = np.broadcast_to(np.asarray(floor, dtype=np.float64), values.shape[:1])
    values[np.abs(values) <= floor.reshape(-1, *([1] * (values.ndim - 1)))] = 0.0
    return values


def clean_contact(rows: ContactRows) -> ContactRows:
    """Contact rows (``output_values.ContactRows``) with values within their accuracy as 0.

    ``rows.accuracy`` holds the length accuracy and each row's pressure and energy accuracies
    (:func:`law_accuracy`); clearance and slips are lengths. Rows without it are unchanged.
    """
    if rows.accuracy is None:
        return rows
    length, pressure, energy = rows.accuracy
    return dataclasses.replace(
        rows,
        clearance=zero_below(rows.clearance, length),
        pressure=zero_below(rows.pressure, pressure),
        energy=zero_below(rows.energy, energy),
        slip=None if rows.slip is None else zero_below(rows.slip, length),
    )


def element_sizes(coordinates: np.ndarray, connectivity: np.ndarray) -> tuple[float, float]:
    """The smallest and the largest distance between two nodes of one element (0 without).

    ``connectivity`` ``(E, n)`` holds row indices into ``coordinates`` ``(N, 3)``.
    """
    if connectivity.size == 0:
        return 0.0, 0.0
    x = coordinates[connectivity]  # (E, n, 3)
    smallest, largest = np.inf, 0.0
    for k in range(1, connectivity.shape[1]):  # node pairs (i, i + k)
        distance = np.linalg.norm(x[:, k:] - x[:, :-k], axis=-1)
        smallest, largest = min(smallest, distance.min()), max(largest, distance.max())
    return float(smallest), float(largest)


def largest_modulus(elastic: typing.Iterable[tuple[float, float]]) -> float:
    """The largest ``lambda + 2 mu = E (1 - nu) / ((1 + nu) (1 - 2 nu))`` of ``(E, nu)`` pairs."""
    moduli = [e * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) for e, nu in elastic]
    return max(moduli, default=0.0)
