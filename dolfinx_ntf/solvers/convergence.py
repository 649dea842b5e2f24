"""When a Newton iteration has converged or diverged: CalculiX's rules for the mechanical field.

:class:`ForceScaledTest` is the force-scaled test of ``*CONTROLS, PARAMETERS=FIELD``
(docs/method.md §7.1) with the forces it remembers over an increment and a step;
:class:`DivergenceRule` gives an increment up when the residual grows; :class:`ExtraPairings` counts
the pairings a solve adds for penetrating slave nodes without a spring. Both only compute, on
numbers that the Newton solver hands over; :func:`measure_iterate` (collective) measures them.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass, field

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.solvers.errors import ContactConvergenceError, ContactDivergenceError

__all__ = [
    "CCX_FIELD_CONTROLS",
    "DIVERGENCE_GROWTH",
    "DIVERGENCE_RULES",
    "ITERATIONS_PER_EXTRA_PAIRING",
    "MAX_EXTRA_PAIRINGS",
    "SCALE_GROWTH",
    "TIGHT_FIELD_CONTROLS",
    "DivergenceRule",
    "ExtraPairings",
    "ForceScaledTest",
    "RoundoffFloor",
    "measure_iterate",
]

#: CalculiX's defaults of ``*CONTROLS, PARAMETERS=FIELD`` (mechanical field).
CCX_FIELD_CONTROLS: dict[str, float] = {
    "R_n": 0.005,
    "C_n": 0.01,
    "R_p": 0.02,
    "R_l": 1e-8,
    "epsilon": 1e-5,
    "C_epsilon": 1e-3,
}
#: Field controls that converge to round-off level: the default of
#: :class:`~dolfinx_ntf.ContactNewtonSolver` and of ``dolfinx-ntf run --tight``.
TIGHT_FIELD_CONTROLS: dict[str, float] = {
    "R_n": 1e-10,
    "C_n": 1e-8,
    "R_p": 1e-10,
    "R_l": 1e-12,
    "epsilon": 1e-5,
    "C_epsilon": 1e-8,
}

#: The ``"growth"`` divergence rule's margin: a residual counts as larger than an earlier one when
#: it exceeds it by this factor, so that iterations that stagnate on a plateau go on (the
#: ``"ccx"`` rule compares strictly, as CalculiX does, and spares residuals below its tolerance).
DIVERGENCE_GROWTH = 1.01

#: With a bounded scale (:class:`ForceScaledTest`), an iterate's average force counts in the mean
#: up to this multiple of the forces known to be sound: the predictor's, the first update's and
#: those of the converged increments.
SCALE_GROWTH = 1e3

#: Pairings a solve may add to CalculiX's schedule for slave nodes that penetrate without a spring.
MAX_EXTRA_PAIRINGS = 3
#: Newton iterations each extra pairing adds to ``max_it`` (the set changes: Newton starts over).
ITERATIONS_PER_EXTRA_PAIRING = 10


def measure_iterate(
    problem: ContactProblem,
    x: PETSc.Vec,
    b: PETSc.Vec,
    dx: PETSc.Vec,
    relaxation: float,
    start: np.ndarray,
) -> tuple[float, float, float, float]:
    """What the force-scaled test reads of an iterate ``x`` with residual ``b``. Collective.

    Returns:
        ``q``, the average element force (:meth:`ContactProblem.average_element_force`);
        ``r``, the largest residual force; the largest correction ``relaxation * dx`` (before
        the line search's step); ``du``, the largest change of ``x`` from ``start`` (all
        processes).
    """
    average = problem.average_element_force()
    largest = b.norm(PETSc.NormType.NORM_INFINITY)
    correction = relaxation * dx.norm(PETSc.NormType.NORM_INFINITY)
    change = float(np.abs(x.array - start[: x.array.size]).max(initial=0.0))
    change = problem.u.function_space.mesh.comm.allreduce(change, op=MPI.MAX)
    return average, largest, correction, change


#: Round-off of a residual force, in units of machine epsilon times the Jacobian's largest row sum
#: and the largest coordinate (:func:`roundoff_floor`).
ROUNDOFF_FACTOR = 10.0


class RoundoffFloor(typing.NamedTuple):
    """Round-off of the residual forces: of the spring rows and of the others (bulk rows)."""

    springs: float
    bulk: float


def roundoff_floor(problem: ContactProblem, A: PETSc.Mat, x: PETSc.Vec) -> RoundoffFloor:
    """The round-off of the residual forces at ``x``. Collective.

    A spring force is a stiffness times a gap taken between current coordinates, so it carries
    about ``eps K A |x|`` of round-off: ``10 eps ||A||_inf max |X + u|`` (the Jacobian's largest
    row sum bounds ``K A``). A bulk force ``K u`` computed in floating point carries about
    ``eps ||K||_inf max |u|``: ``10 eps`` times the bulk Jacobian's largest row sum
    (:attr:`ContactProblem.bulk_norm`) and the largest displacement. Either can exceed what the
    force-scaled test asks (``R_n`` times the mean element force, which small elements far from
    the contact pull down), e.g. the large element forces under a contact with a
    St.Venant-Kirchhoff bulk. :func:`largest_beyond_roundoff` leaves residuals below them out.
    """
    comm = problem.u.function_space.mesh.comm
    displacement = float(np.abs(x.array_r).max(initial=0.0))
    coordinates = float(np.abs(problem.reference_coordinates).max(initial=0.0)) + displacement
    sizes = np.array([coordinates, displacement])
    comm.Allreduce(MPI.IN_PLACE, sizes, op=MPI.MAX)
    coordinates, displacement = sizes
    epsilon = ROUNDOFF_FACTOR * np.finfo(float).eps
    return RoundoffFloor(
        epsilon * A.norm(PETSc.NormType.NORM_INFINITY) * coordinates,
        epsilon * problem.bulk_norm * displacement,
    )


def largest_beyond_roundoff(problem: ContactProblem, b: PETSc.Vec, floor: RoundoffFloor) -> float:
    """The largest residual force of ``b``, the entries below their round-off ``floor`` left out.

    Collective. Rows where springs act (from every process's springs: the same on any
    partition) take the springs' floor, the others the bulk's.
    """
    sizes = b.duplicate()
    problem.spring_force_sizes(sizes)
    values = np.abs(b.array_r)
    spring_rows = sizes.array_r > 0.0
    sizes.destroy()
    values[spring_rows & (values < floor.springs)] = 0.0
    values[~spring_rows & (values < floor.bulk)] = 0.0
    comm = problem.u.function_space.mesh.comm
    return comm.allreduce(float(values.max(initial=0.0)), op=MPI.MAX)


@dataclass
class ForceScaledTest:
    """CalculiX's force-scaled convergence test and the forces it averages.

    Args:
        controls: ``R_n``, ``C_n``, ``R_p``, ``R_l``, ``epsilon``, ``C_epsilon`` (see
            ``TIGHT_FIELD_CONTROLS``).
        relaxation_iteration: CalculiX's I_P: after this many updates ``R_p`` replaces ``R_n``.
        residual_floor: A largest residual force below this absolute value counts as zero (then
            the ``R_l`` test holds). CalculiX 2.20 does this with 1e-6 in the deck's force unit
            (docs/method.md §7.1), which the deck runner reproduces; 0 keeps the test scale-free.
        average_over_step: ``q~`` is the mean over the increments of the step so far (each by
            its last ``q``, the current one by its ``q`` now), CalculiX's time-averaged force,
            which the deck runner reproduces; default: the mean over the iterations of the
            current increment.
        change_over_iterations: ``du`` is the largest over the iterations of the increment so
            far (CalculiX's; the deck runner reproduces it); default: the change now.
        bounded: Beyond CalculiX, a test that runaway iterates cannot pass: in the mean ``q~``
            each ``q`` counts up to ``SCALE_GROWTH`` times the largest sound force (the
            predictor's, the first update's, the converged increments' means); once an iterate's
            residual is back at or below the increment's first, only such settled iterates'
            ``q`` make the mean (a solve that ran away and came back is judged by the forces
            it came back to); and a residual
            larger than the increment's first one (:meth:`begin_iterations`) converges only
            if it passes on the converged increments' scale. CalculiX's scale grows with a
            diverging iterate, so that a residual 46 times the first passed its ``R_l`` test on a
            body with no support (the deck runner keeps CalculiX's test).
    """

    controls: dict[str, float]
    relaxation_iteration: int = 9
    residual_floor: float = 0.0
    average_over_step: bool = False
    change_over_iterations: bool = False
    bounded: bool = False
    #: Mean element force of every converged increment so far (the scale of an unloaded one).
    past_averages: list[float] = field(default_factory=list)
    #: Last average force ``q`` of each converged increment of the current step.
    step_forces: list[float] = field(default_factory=list)
    #: Largest residual force of the last iterate (before ``residual_floor``).
    largest_residual: float = 0.0
    #: ``(r, q~, c, du)`` of the last :meth:`converged` call, as the test used them.
    last: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    #: ``c1 q~`` of the last :meth:`converged` call: the largest residual force it accepts.
    tolerance: float = 0.0
    _averages: list[float] = field(default_factory=list, repr=False)
    #: ``q`` of the iterates whose residual is at most the increment's first (bounded test).
    _settled_averages: list[float] = field(default_factory=list, repr=False)
    _largest: list[float] = field(default_factory=list, repr=False)
    _largest_change: float = field(default=0.0, repr=False)
    _start: tuple[float, float] = field(default=(0.0, 0.0), repr=False)

    def begin_solve(self, change: float) -> None:
        """Forget the iterations of the last solve; ``change`` is the predictor's own ``du``."""
        self._averages, self._largest, self._settled_averages = [], [], []
        self._largest_change = change
        self._start = (0.0, 0.0)

    def begin_iterations(self, average: float, largest: float) -> None:
        """The average and largest residual force of the solve's first iterate (no update yet)."""
        self._start = (average, largest)

    @property
    def residuals(self) -> list[float]:
        """The largest residual force of each update of the solve (after ``residual_floor``)."""
        return self._largest

    def end_solve(self) -> None:
        """Remember the forces of a converged increment."""
        if self._averages:
            self.past_averages.append(float(np.mean(self._settled_averages or self._averages)))
            self.step_forces.append(self._averages[-1])

    def converged(
        self, updates: int, average: float, largest: float, correction: float, change: float
    ) -> bool:
        """The test after Newton update ``updates``.

        With ``r`` the largest residual force, ``c`` the largest correction, ``du`` the largest
        displacement change in the increment, ``q`` the average absolute element nodal force and
        ``q~`` its mean over the updates so far: converged when ``r <= c1 q~`` and at least one
        of ``c <= c2 du``, ``r c / min(r_{i-1}, r_{i-2}) < c2 du``, ``r <= R_l q~``,
        ``q <= epsilon q~``, ``c < 1e-8``; ``(c1, c2)`` is ``(R_n, C_n)`` up to
        ``relaxation_iteration`` updates, ``(R_p, C_n)`` beyond, and ``(epsilon, C_epsilon)``
        under zero flux. Scaled by forces, the test never asks for less than round-off.

        Args:
            updates: Newton updates so far (>= 1).
            average: ``q``, the average absolute element nodal force of the iterate.
            largest: ``r``, the largest residual force.
            correction: ``c``, the largest correction of the update.
            change: ``du``, the largest displacement change in the increment now.
        """
        controls = self.controls
        past = float(np.mean(self.past_averages)) if self.past_averages else 0.0
        if self.bounded:
            sound = max(self._start[0], self._averages[0] if self._averages else average)
            sound = max(sound, max(self.past_averages, default=0.0))
            self._averages.append(min(average, SCALE_GROWTH * sound))
            if largest <= self._start[1]:
                self._settled_averages.append(average)
        else:
            self._averages.append(average)
        mean = float(np.mean(self._settled_averages or self._averages))
        if self.average_over_step:
            mean = (sum(self.step_forces) + average) / (len(self.step_forces) + 1)
        self.largest_residual = largest
        if largest < self.residual_floor:
            largest = 0.0
        self._largest.append(largest)
        if self.change_over_iterations:
            self._largest_change = change = max(self._largest_change, change)
        if mean <= controls["epsilon"] * past:
            # Unloaded (all forces vanish, e.g. a contact pair removed): CalculiX's zero-flux test
            # against the forces of the earlier increments (docs/method.md §11.6).
            mean = past
        if average <= controls["epsilon"] * mean:
            c1, c2 = controls["epsilon"], controls["C_epsilon"]
        else:
            c1 = controls["R_n"] if updates <= self.relaxation_iteration else controls["R_p"]
            c2 = controls["C_n"]
        self.last = (largest, mean, correction, change)
        self.tolerance = c1 * mean
        estimate = np.inf
        if updates >= 3 and min(self._largest[-3:-1]) > 0:
            estimate = largest * correction / min(self._largest[-3:-1])
        if self.bounded and largest > max(self._start[1], c1 * past):
            return False
        return largest <= c1 * mean and (
            correction <= c2 * change
            or estimate < c2 * change
            or largest <= controls["R_l"] * mean
            or average <= controls["epsilon"] * mean
            or correction < 1e-8
        )


#: Names of the divergence rules (:class:`DivergenceRule`): ``"growth"`` is the Python API's
#: default, ``"ccx"`` CalculiX 2.20's (the deck runner's).
DIVERGENCE_RULES = ("growth", "ccx")


class DivergenceRule:
    """When a growing residual ends an attempt (docs/method.md §42).

    ``"growth"``: a residual larger than ``DIVERGENCE_GROWTH`` times each of the two before it,
    on the residual's 2-norm. ``"ccx"``: CalculiX 2.20's check on the largest residual force
    ``r_k``: the last two both larger than the one before them (``r_{k-1} > r_{k-2}`` and
    ``r_k > r_{k-2}``) and the last above the force-scaled test's tolerance (``r_k > c1 q~``,
    :attr:`ForceScaledTest.tolerance`), so that an iterate that stagnates below the tolerance
    is never given up. Both check from update ``first_iteration`` on.

    Args:
        first_iteration: CalculiX's I_0, the first Newton update checked.
        rule: One of ``DIVERGENCE_RULES``.
    """

    def __init__(self, first_iteration: int, rule: str = "growth") -> None:
        if rule not in DIVERGENCE_RULES:
            raise ValueError(f"divergence rule must be one of {DIVERGENCE_RULES}, got {rule!r}")
        self.first_iteration = first_iteration
        self.first_check = first_iteration
        self.rule = rule

    def reset(self) -> None:
        """Start a solve: check from ``first_iteration`` on."""
        self.first_check = self.first_iteration

    def defer(self, updates: int, by: int) -> None:
        """Check no earlier than ``by`` updates after ``updates`` (the springs changed)."""
        self.first_check = max(self.first_check, updates + by)

    def diverges(self, updates: int, residuals: typing.Sequence[float], tolerance: float) -> bool:
        """Whether the attempt ends after update ``updates``.

        Args:
            updates: Newton updates so far.
            residuals: The measures of the iterates so far, the current one last (2-norms for
                ``"growth"``, largest residual forces for ``"ccx"``).
            tolerance: The residual the force-scaled test accepts now (``"ccx"`` only).
        """
        if updates < self.first_check or len(residuals) < 3:
            return False
        before, last, now = residuals[-3], residuals[-2], residuals[-1]
        if self.rule == "ccx":
            return last > before and now > before and now > tolerance
        return now > DIVERGENCE_GROWTH * max(last, before)

    def check(
        self,
        updates: int,
        residuals: typing.Sequence[float],
        hint: typing.Callable[[], str],
        tolerance: float = 0.0,
    ) -> None:
        """Raise :class:`~dolfinx_ntf.ContactDivergenceError` if :meth:`diverges`.

        ``hint()`` words a likely cause for the message (called only when raising).
        """
        if self.diverges(updates, residuals, tolerance):
            what = "largest residual force" if self.rule == "ccx" else "residual"
            above = f" (tolerance {tolerance:.3e})" if self.rule == "ccx" else ""
            values = ", ".join(f"{r:.3e}" for r in residuals[-3:])
            raise ContactDivergenceError(
                f"{what} grows: {values}{above} after {updates} Newton updates{hint()}"
            )


class ExtraPairings:
    """Pairings beyond CalculiX's schedule for slave nodes that penetrate without a spring.

    CalculiX freezes the pairing after Newton iteration 8, so such nodes can remain at
    convergence; a solve pairs again instead and iterates on, at most ``MAX_EXTRA_PAIRINGS``
    times per increment, then gives the increment up.
    """

    def __init__(self) -> None:
        self.count = 0

    def take(self, unpaired: int) -> int:
        """One more pairing for ``unpaired`` nodes; returns the Newton iterations it adds.

        Raises:
            ContactConvergenceError: The solve has used all its extra pairings.
        """
        if self.count >= MAX_EXTRA_PAIRINGS:
            raise ContactConvergenceError(
                f"{unpaired} slave node(s) still penetrate the master without a spring after "
                f"{MAX_EXTRA_PAIRINGS} extra pairings"
            )
        self.count += 1
        return ITERATIONS_PER_EXTRA_PAIRING
