"""Comparison of ccx results with dolfinx_ntf results on the same deck.

Both sides are first brought to the same neutral form, :class:`IncrementResults` (one converged
increment: displacements per ccx node number and the contact rows of ``*CONTACT PRINT`` in contact
element order), then :func:`compare_increments` matches increments by total time and returns the
largest differences with the scales they should be judged against. :func:`compare_job` does both
steps for a ccx ``.dat`` file and a :class:`~dolfinx_ntf.calculix.job.JobResult`.

Scales, per increment (the tests and ``benchmarks/validate.py`` divide by them):
    - displacements: the largest displacement component of ccx's increment;
    - contact pressure: the largest ``|p|`` of ccx's contact rows;
    - clearance: the largest ``|g|`` of ccx's contact rows;
    - energy: the largest spring energy of ccx's contact rows.
Values are compared for the slave nodes that have a contact element on both sides; whether the two
sides have the same contact elements is reported separately.
"""

from __future__ import annotations

import math
import typing
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .dat import DatBlock, read_dat

if typing.TYPE_CHECKING:
    from .job import JobResult

__all__ = [
    "Comparison",
    "IncrementComparison",
    "IncrementResults",
    "ccx_increments",
    "compare_increment",
    "compare_increments",
    "compare_job",
    "job_increments",
]

#: Relative tolerance when matching increment times (ccx prints times with 7 significant digits).
TIME_TOLERANCE = 1e-6


@dataclass(frozen=True, eq=False)
class IncrementResults:
    """Results of one converged increment in ccx numbering.

    Attributes:
        time: Total time at the end of the increment.
        node_ids: ``(N,)`` ccx node numbers.
        displacements: ``(N, 3)`` displacements of those nodes.
        contact_nodes: ``(S,)`` slave node of each contact element, in ccx element order (pairs in
            deck order, slave nodes ascending within a pair).
        clearance: ``(S,)`` clearance g (negative = penetration), ccx's CDIS normal column.
        pressure: ``(S,)`` contact pressure (compression > 0), ccx's CSTR press column.
        energy: ``(S,)`` spring energy (CELS), or None if not available.
        iterations: Newton iterations of the increment, or None if unknown.
        slip: ``(S, 2)`` CDIS tangential columns, or None.
        shear: ``(S, 2)`` CSTR tangential columns, or None.
    """

    time: float
    node_ids: np.ndarray
    displacements: np.ndarray
    contact_nodes: np.ndarray
    clearance: np.ndarray
    pressure: np.ndarray
    energy: np.ndarray | None = None
    iterations: int | None = None
    slip: np.ndarray | None = None
    shear: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class IncrementComparison:
    """Largest differences of one increment, and the ccx scales to judge them by.

    Attributes:
        time: Total time of the increment.
        displacement: Largest ``|u_ccx - u_ntf|`` over common nodes and components.
        displacement_scale: Largest ``|u_ccx|``.
        pressure, pressure_scale: Same for the contact pressure of common contact elements.
        clearance, clearance_scale: Same for the clearance.
        energy, energy_scale: Same for the spring energy (NaN when a side has no energies).
        ccx_contact, ntf_contact: Sorted slave nodes with a contact element on each side.
        missing_nodes: Displacement node numbers present on one side only.
        ccx_iterations, ntf_iterations: Newton iterations (None if unknown).
        slip, slip_scale, shear, shear_scale: Same for the tangential CDIS and CSTR columns.
    """

    time: float
    displacement: float
    displacement_scale: float
    pressure: float
    pressure_scale: float
    clearance: float
    clearance_scale: float
    energy: float
    energy_scale: float
    ccx_contact: np.ndarray
    ntf_contact: np.ndarray
    missing_nodes: np.ndarray
    ccx_iterations: int | None = None
    ntf_iterations: int | None = None
    slip: float = math.nan
    slip_scale: float = math.nan
    shear: float = math.nan
    shear_scale: float = math.nan

    @property
    def relative_slip(self) -> float:
        """Tangential relative displacement difference over the largest ccx value."""
        return _ratio(self.slip, self.slip_scale)

    @property
    def relative_shear(self) -> float:
        """Shear traction difference over the largest ccx shear traction."""
        return _ratio(self.shear, self.shear_scale)

    @property
    def same_contact_elements(self) -> bool:
        """True if both sides have contact elements for exactly the same slave nodes."""
        return np.array_equal(self.ccx_contact, self.ntf_contact)

    @property
    def relative_displacement(self) -> float:
        """Displacement difference over the largest ccx displacement."""
        return _ratio(self.displacement, self.displacement_scale)

    @property
    def relative_pressure(self) -> float:
        """Pressure difference over the largest ccx pressure."""
        return _ratio(self.pressure, self.pressure_scale)

    @property
    def relative_clearance(self) -> float:
        """Clearance difference over the largest ccx clearance."""
        return _ratio(self.clearance, self.clearance_scale)

    @property
    def relative_energy(self) -> float:
        """Energy difference over the largest ccx energy."""
        return _ratio(self.energy, self.energy_scale)


def _ratio(value: float, scale: float) -> float:
    if math.isnan(value):
        return math.nan
    if scale > 0:
        return value / scale
    return 0.0 if value == 0 else math.inf


@dataclass(frozen=True, eq=False)
class Comparison:
    """Comparison of all increments of a run.

    Attributes:
        increments: One entry per increment present on both sides, in time order.
        ccx_only, ntf_only: Times of increments present on one side only.
    """

    increments: tuple[IncrementComparison, ...]
    ccx_only: tuple[float, ...] = ()
    ntf_only: tuple[float, ...] = ()

    def _max(self, name: str) -> float:
        values = [getattr(c, name) for c in self.increments]
        values = [v for v in values if not math.isnan(v)]
        return max(values, default=0.0)

    @property
    def relative_displacement(self) -> float:
        """Largest relative displacement difference over the increments."""
        return self._max("relative_displacement")

    @property
    def relative_pressure(self) -> float:
        """Largest relative contact pressure difference over the increments."""
        return self._max("relative_pressure")

    @property
    def relative_clearance(self) -> float:
        """Largest relative clearance difference over the increments."""
        return self._max("relative_clearance")

    @property
    def relative_energy(self) -> float:
        """Largest relative spring energy difference over the increments."""
        return self._max("relative_energy")

    @property
    def relative_slip(self) -> float:
        """Largest relative tangential displacement (CDIS) difference over the increments."""
        return self._max("relative_slip")

    @property
    def relative_shear(self) -> float:
        """Largest relative shear traction (CSTR) difference over the increments."""
        return self._max("relative_shear")

    @property
    def clearance(self) -> float:
        """Largest absolute clearance difference over the increments."""
        return self._max("clearance")

    @property
    def same_increments(self) -> bool:
        """True if both sides converged at the same times."""
        return not self.ccx_only and not self.ntf_only

    @property
    def same_contact_elements(self) -> bool:
        """True if every common increment has the same contact elements on both sides."""
        return all(c.same_contact_elements for c in self.increments)

    def contact_differences(self) -> list[str]:
        """One line per increment whose contact elements differ (slave nodes on one side only)."""
        lines = []
        for c in self.increments:
            if not c.same_contact_elements:
                only_ccx = np.setdiff1d(c.ccx_contact, c.ntf_contact)
                only_ntf = np.setdiff1d(c.ntf_contact, c.ccx_contact)
                lines.append(
                    f"time {c.time:.7g}: ccx only {only_ccx.tolist()}, dolfinx_ntf only "
                    f"{only_ntf.tolist()} ({c.ccx_contact.size} vs {c.ntf_contact.size} elements)"
                )
        return lines

    def summary(self) -> str:
        """Summarize the comparison in a few lines for messages and logs."""
        lines = [
            f"{len(self.increments)} common increments; max relative differences: displacement "
            f"{self.relative_displacement:.3g}, pressure {self.relative_pressure:.3g}, clearance "
            f"{self.relative_clearance:.3g} (absolute {self.clearance:.3g}), energy "
            f"{self.relative_energy:.3g}"
            + (
                f", slip {self.relative_slip:.3g}, shear {self.relative_shear:.3g}"
                if self.relative_shear > 0 or self.relative_slip > 0
                else ""
            )
        ]
        if self.ccx_only or self.ntf_only:
            lines.append(f"increments of ccx only at {list(self.ccx_only)}, dolfinx_ntf only at "
                         f"{list(self.ntf_only)}")  # fmt: skip
        lines += self.contact_differences()
        return "\n".join(lines)


# ----------------------------------------------------------------------------- ccx side


def ccx_increments(
    blocks: Sequence[DatBlock] | str | Path, sta: Sequence | None = None
) -> list[IncrementResults]:
    """Increments of a ccx ``.dat`` file with ``*NODE PRINT`` U and ``*CONTACT PRINT`` CDIS, CSTR.

    Args:
        blocks: Blocks from :func:`~dolfinx_ntf.calculix.dat.read_dat`, or the ``.dat`` path.
        sta: Rows of :func:`~dolfinx_ntf.calculix.ccx.read_sta` (adds iterations per increment).

    Raises:
        ValueError: A time with displacements but without CDIS/CSTR blocks, or contact blocks whose
            rows disagree.
    """
    if isinstance(blocks, (str, Path)):
        blocks = read_dat(blocks)
    by_time: dict[float, dict[str, list[DatBlock]]] = {}
    for block in blocks:
        if block.name in ("U", "CDIS", "CSTR", "CELS"):
            by_time.setdefault(block.time, {}).setdefault(block.name, []).append(block)
    iterations = {}
    for row in sta or ():
        iterations[round(row.total_time, 6)] = row.iterations
    results = []
    for time, named in by_time.items():
        if "U" not in named:
            continue
        for name in ("CDIS", "CSTR"):
            if name not in named:
                raise ValueError(f"ccx .dat: no {name} block at time {time} (add *CONTACT PRINT)")
        node_ids = np.concatenate([b.labels for b in named["U"]])
        displacements = np.concatenate([b.values for b in named["U"]])
        node_ids, first = np.unique(node_ids, return_index=True)  # several node prints: once each
        cdis, cstr = named["CDIS"][-1], named["CSTR"][-1]
        if not np.array_equal(cdis.labels, cstr.labels):
            raise ValueError(f"ccx .dat: CDIS and CSTR rows differ at time {time}")
        energy = None
        if "CELS" in named and np.array_equal(named["CELS"][-1].labels, cdis.labels):
            energy = named["CELS"][-1].values[:, 0]
        results.append(
            IncrementResults(
                time=time,
                node_ids=node_ids,
                displacements=displacements[first],
                contact_nodes=cdis.labels.astype(np.int64),
                clearance=cdis.values[:, 0],
                pressure=cstr.values[:, 0],
                energy=energy,
                iterations=iterations.get(round(time, 6)),
                slip=cdis.values[:, 1:3] if cdis.values.shape[1] >= 3 else None,
                shear=cstr.values[:, 1:3] if cstr.values.shape[1] >= 3 else None,
            )
        )
    return results


# ----------------------------------------------------------------------------- dolfinx_ntf side


def job_increments(job: JobResult) -> list[IncrementResults]:
    """Increments of a :class:`~dolfinx_ntf.calculix.job.JobResult` in the neutral form."""
    results = []
    for inc in job.increments:
        rows = list(inc.contact)
        nodes = [np.asarray(r.nodes, dtype=np.int64) for r in rows]
        results.append(
            IncrementResults(
                time=float(inc.time),
                node_ids=np.asarray(inc.node_ids, dtype=np.int64),
                displacements=np.asarray(inc.displacement, dtype=float).reshape(-1, 3),
                contact_nodes=np.concatenate(nodes) if nodes else np.zeros(0, np.int64),
                clearance=_cat([r.clearance for r in rows]),
                pressure=_cat([r.pressure for r in rows]),
                energy=_cat([r.energy for r in rows]),
                iterations=int(inc.iterations),
                slip=_cat2([r.slip for r in rows]),
                shear=_cat2([r.shear for r in rows]),
            )
        )
    return results


def _cat(arrays: list) -> np.ndarray:
    return np.concatenate([np.asarray(a, dtype=float) for a in arrays]) if arrays else np.zeros(0)


def _cat2(arrays: list) -> np.ndarray | None:
    if any(a is None for a in arrays):
        return None
    return (
        np.concatenate([np.asarray(a, dtype=float).reshape(-1, 2) for a in arrays])
        if arrays
        else np.zeros((0, 2))
    )


# ----------------------------------------------------------------------------- comparison


def _match(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return indices of the common labels of ``a`` and ``b`` (repeats matched in order)."""
    order_a = np.argsort(a, kind="stable")
    order_b = np.argsort(b, kind="stable")
    sa, sb = a[order_a], b[order_b]
    # occurrence number of each label, so that a node in two pairs is matched pairwise
    occ_a = np.arange(sa.size) - np.searchsorted(sa, sa, side="left")
    occ_b = np.arange(sb.size) - np.searchsorted(sb, sb, side="left")
    key_a = np.stack([sa, occ_a], axis=1)
    key_b = np.stack([sb, occ_b], axis=1)
    _, ia, ib = np.intersect1d(
        key_a.view([("n", np.int64), ("o", np.int64)]).ravel(),
        key_b.view([("n", np.int64), ("o", np.int64)]).ravel(),
        return_indices=True,
    )
    return order_a[ia], order_b[ib]


def _max_abs(values: np.ndarray) -> float:
    return float(np.max(np.abs(values))) if values.size else 0.0


def compare_increment(ccx: IncrementResults, ntf: IncrementResults) -> IncrementComparison:
    """Largest differences between two results of the same increment."""
    i, j = _match(ccx.node_ids, ntf.node_ids)
    missing = np.setxor1d(ccx.node_ids, ntf.node_ids)
    du = _max_abs(ccx.displacements[i] - ntf.displacements[j])
    k, m = _match(ccx.contact_nodes, ntf.contact_nodes)
    energy = scale_energy = math.nan
    if ccx.energy is not None and ntf.energy is not None:
        energy = _max_abs(ccx.energy[k] - ntf.energy[m])
        scale_energy = _max_abs(ccx.energy)
    tangential = {}
    for name in ("slip", "shear"):
        a, b = getattr(ccx, name), getattr(ntf, name)
        if a is not None and b is not None:
            tangential[name] = _max_abs(a[k] - b[m])
            tangential[f"{name}_scale"] = _max_abs(a)
    return IncrementComparison(
        **tangential,
        time=ccx.time,
        displacement=du,
        displacement_scale=_max_abs(ccx.displacements),
        pressure=_max_abs(ccx.pressure[k] - ntf.pressure[m]),
        pressure_scale=_max_abs(ccx.pressure),
        clearance=_max_abs(ccx.clearance[k] - ntf.clearance[m]),
        clearance_scale=_max_abs(ccx.clearance),
        energy=energy,
        energy_scale=scale_energy,
        ccx_contact=np.sort(ccx.contact_nodes),
        ntf_contact=np.sort(ntf.contact_nodes),
        missing_nodes=missing,
        ccx_iterations=ccx.iterations,
        ntf_iterations=ntf.iterations,
    )


def compare_increments(
    ccx: Sequence[IncrementResults], ntf: Sequence[IncrementResults]
) -> Comparison:
    """Compare the increments of two runs, matched by total time."""
    used = np.zeros(len(ntf), dtype=bool)
    matched = []
    ccx_only = []
    for result in ccx:  # loop over a handful of increments
        tol = TIME_TOLERANCE * max(1.0, abs(result.time))
        found = [k for k, r in enumerate(ntf) if not used[k] and abs(r.time - result.time) <= tol]
        if not found:
            ccx_only.append(result.time)
            continue
        used[found[0]] = True
        matched.append(compare_increment(result, ntf[found[0]]))
    ntf_only = tuple(r.time for k, r in enumerate(ntf) if not used[k])
    return Comparison(tuple(matched), tuple(ccx_only), ntf_only)


def compare_job(
    dat: str | Path | Sequence[DatBlock], job: JobResult, sta: Sequence | None = None
) -> Comparison:
    """Compare a ccx ``.dat`` file (path or blocks) with a ``JobResult`` of the same deck.

    Args:
        dat: ccx's ``.dat`` file or its blocks (``*NODE PRINT`` U, ``*CONTACT PRINT`` CDIS, CSTR).
        job: What :func:`~dolfinx_ntf.calculix.job.run_job` returned.
        sta: ccx's ``.sta`` rows (:func:`~dolfinx_ntf.calculix.ccx.read_sta`), for iterations.
    """
    return compare_increments(ccx_increments(dat, sta), job_increments(job))
