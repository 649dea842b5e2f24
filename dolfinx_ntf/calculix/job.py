"""Run a CalculiX deck like ``ccx``: read ``JOB.inp``, solve, write ccx's files and ``JOB.xdmf``.

``run_job`` builds the model (``model/``), runs each ``*STEP`` with
:class:`~dolfinx_ntf.StaticStep` (``*STATIC`` initial increment, period, minimum, maximum;
``DIRECT`` = fixed increments) or :class:`~dolfinx_ntf.DynamicStep` (``*DYNAMIC``), counts steps,
increments and attempts as ccx does and, per converged increment that the output FREQUENCY
selects, has :class:`~dolfinx_ntf.calculix.job_files.JobFiles` write ``JOB.dat``, ``.frd``,
``.cel``, ``.sta`` and ``.cvg`` in ccx 2.20's formats (docs/method.md §8.5, §13.2, §13.3) from the
values of :class:`~dolfinx_ntf.calculix.output_values.OutputValues`. ``JOB.xdmf`` holds the
displacement, contact pressure, clearance and status of every converged increment. RF is the
internal force of the bulk elements plus the contact springs at each node, as ccx prints it: the
reaction at constrained dofs, the applied load elsewhere.

Newton stops like ccx (manual "Convergence criteria"): the largest residual force component must
fall below ``R_n`` (``*CONTROLS, PARAMETERS=FIELD``, default 0.005) times the average element force,
averaged over the iterations of the increment (``R_p`` after ``I_P`` iterations), and the last
correction must be small against the increment's displacement change (``C_n``), see
:meth:`ContactNewtonSolver.is_converged`. ``tight=True`` replaces the deck's values by
``TIGHT_FIELD_CONTROLS`` (``R_n = R_p = 1e-10``, ``controls.py``), so that converged solutions are
compared.

Steps without contact pairs, NLGEOM and temperatures are linear: one increment over the whole
step, as in ccx (whose thermal steps follow their increments also without contact, §39).

Under ``mpirun -n N`` the model is distributed by dolfinx and every output is gathered in ccx
numbering (``gather.py``) and written by rank 0: the files are those of the serial run
(docs/method.md §14.5, §14.9, §14.10).
"""

from __future__ import annotations

import dataclasses
import logging
import time as _time
import typing
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.kernels.laws import LinearLaw
from dolfinx_ntf.logs import log_progress
from dolfinx_ntf.outputs.results import ContactWriter
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.factor_reuse import FACTORIZATIONS
from dolfinx_ntf.solvers.newton import ContactNewtonSolver
from dolfinx_ntf.solvers.steps import IncrementResult, StaticStep

from .controls import relaxation_iteration, solver_controls
from .dat import CCX_FORMATS
from .deck import Deck, PrintRequest, Step, read_deck
from .gather import CcxNumbering
from .job_files import JobFiles, check_requests
from .model import CalculixModel, build_model, friction_of
from .output_values import ContactRows, OutputValues
from .xdmf import WedgeDeckWriter

if typing.TYPE_CHECKING:
    from dolfinx_ntf.solvers.modes import Modes

    from .coupled import CoupledIncrementSolver, HeatIncrementSolver, SequentialIncrementSolver

# The modules of dynamic, modal and coupled steps are imported where such a step runs: a static
# deck does not pay for them at start-up (docs/performance.md, "Start-up").

__all__ = ["ContactRows", "IncrementOutput", "JobError", "JobResult", "run_job"]

logger = logging.getLogger("dolfinx_ntf")

#: CalculiX 2.20 counts a largest residual force below this (in the deck's force unit) as zero
#: in its convergence test (measured, docs/method.md §7.1); not with ``tight=True``.
CCX_RESIDUAL_FLOOR = 1e-6

#: With ``tangent="auto"``, from this many dofs on the deck runner uses CalculiX's symmetrized
#: contact tangent, whose Cholesky factorization costs about half an LU; below, the exact tangent,
#: which converges in fewer iterations where projections are clamped to a face edge
#: (docs/method.md §7.4).
SYMMETRIC_MIN_DOFS = 10_000

#: The deck runner's spring tangents (``run_job(tangent=...)``, ``--tangent``).
TANGENTS: tuple[str, ...] = ("ccx", "exact", "auto")

#: Initial accelerations of ``*DYNAMIC`` steps (``run_job(initial_acceleration=...)``).
INITIAL_ACCELERATIONS: tuple[str, ...] = ("ccx", "exact")


class JobError(RuntimeError):
    """A job that stopped early (e.g. no convergence); files keep the converged increments.

    ``message`` says why.

    Attributes:
        exit_code: Exit status for the command line (2: no convergence).
        result: The :class:`JobResult` of the converged increments.
    """

    def __init__(
        self, message: str, *, exit_code: int = 2, result: JobResult | None = None
    ) -> None:
        super().__init__(message)
        self.exit_code = exit_code
        self.result = result


@dataclass(frozen=True, eq=False)
class IncrementOutput:
    """Results of one converged increment.

    Attributes:
        step, increment, attempt: 1-based numbers (increments restart in every step).
        iterations: Newton iterations of the converged attempt.
        step_time, time: Step time and total time at the end of the increment.
        node_ids: ``(n,)`` ccx node numbers of the mesh, ascending.
        displacement: ``(n, 3)`` displacements of those nodes.
        contact: Contact rows per pair, pairs in deck order.
    """

    step: int
    increment: int
    attempt: int
    iterations: int
    step_time: float
    time: float
    node_ids: np.ndarray
    displacement: np.ndarray
    contact: list[ContactRows]

    @property
    def slave_nodes(self) -> set[int]:
        """Ccx numbers of the slave nodes that have a contact element (all pairs)."""
        return {int(n) for rows in self.contact for n in rows.nodes}

    def displacement_of(self, node_ids: np.ndarray | Sequence[int]) -> np.ndarray:
        """Displacements ``(k, 3)`` of ccx node numbers."""
        ids = np.asarray(node_ids, dtype=np.int64)
        pos = np.searchsorted(self.node_ids, ids)
        if np.any(pos >= self.node_ids.size) or np.any(
            self.node_ids[np.minimum(pos, self.node_ids.size - 1)] != ids
        ):
            raise ValueError(f"node(s) {ids.tolist()} are not all mesh nodes")
        return self.displacement[pos]


@dataclass(eq=False)
class JobResult:
    """What ``run_job`` did.

    Attributes:
        jobname, directory: The job.
        model: The dolfinx model of the deck.
        increments: Every converged increment, in order.
        dat, cel, frd, xdmf: Files written (``cel`` is None without CONTACT ELEMENTS).
        completed: True if every step ran to its end.
        wall_time: Seconds spent in ``run_job``.
        eigenvalues: ``omega^2`` of the last ``*FREQUENCY`` step's modes (None without one).
    """

    jobname: str
    directory: Path
    model: CalculixModel
    increments: list[IncrementOutput] = field(default_factory=list)
    dat: Path | None = None
    cel: Path | None = None
    xdmf: Path | None = None
    frd: Path | None = None
    completed: bool = False
    wall_time: float = 0.0
    eigenvalues: np.ndarray | None = None

    def increment(self, step: int, increment: int) -> IncrementOutput:
        """The output of ``increment`` of ``step`` (1-based)."""
        for out in self.increments:
            if out.step == step and out.increment == increment:
                return out
        raise KeyError(f"no converged increment {increment} in step {step}")

    @property
    def last(self) -> IncrementOutput:
        """The last converged increment."""
        if not self.increments:
            raise ValueError("no increment converged")
        return self.increments[-1]


# ----------------------------------------------------------------------------- the job


@dataclass
class _Counters:
    step: int = 1
    increment: int = 1
    attempt: int = 0


class _Job:
    """The run of one deck: the model, problem, solver, files and the step and attempt counters."""

    def __init__(
        self,
        jobname: str,
        directory: Path,
        deck: Deck,
        model: CalculixModel,
        comm: MPI.Comm,
        *,
        tight: bool,
        problem_options: dict,
        petsc_options: dict | None,
        predictor: bool = False,
        pair_after_predictor: bool = False,
        guard_predictor: bool = True,
        ccx_format: str = "2.20",
        solver_options: dict | None = None,
        initial_acceleration: str = "ccx",
        elastic_contact: str = "start",
    ) -> None:
        self.deck, self.model, self.comm, self.tight = deck, model, comm, tight
        self.initial_acceleration = initial_acceleration
        self.predictor = predictor
        self.elastic_contact = elastic_contact
        self.guard_predictor = guard_predictor
        self.pair_after_predictor = pair_after_predictor
        # rank 0 writes the files (docs/method.md §14.5)
        self.files = JobFiles(jobname, directory, deck, model, root=comm.rank == 0, ccx=ccx_format)
        self.result = JobResult(jobname, directory, model)
        self.result.dat, self.result.cel, self.result.frd = (
            self.files.dat,
            self.files.cel,
            self.files.frd,
        )
        self.counters = _Counters()

        v = ufl.TestFunction(model.V)
        internal = model.internal_force
        if internal is None:
            internal = ufl.inner(model.first_piola, ufl.grad(v)) * model.dx
        self.problem = model.create_problem(
            model.begin_step(0), element_forces=internal, **problem_options
        )
        self.problem.pairing_callbacks.append(self._on_pairing)
        # RF as ccx prints it (CAX: without the hoop term, docs/method.md §23)
        printed = internal if model.printed_force is None else model.printed_force
        self.numbering = CcxNumbering(model, printed)
        self.values = OutputValues(deck, model, self.problem, self.numbering, comm)
        self.solver: (
            ContactNewtonSolver
            | CoupledIncrementSolver
            | HeatIncrementSolver
            | SequentialIncrementSolver
        )
        if model.thermal is not None:
            from .coupled import (
                CoupledIncrementSolver,
                HeatIncrementSolver,
                SequentialIncrementSolver,
            )
        if model.thermal is not None and deck.steps[0].coupled.heat:  # all *HEAT TRANSFER
            self.solver = HeatIncrementSolver(self.problem, model.thermal)
        elif model.thermal is not None and model.thermal.constraints:  # C3D15, no contact (§39)
            self.solver = SequentialIncrementSolver(
                HeatIncrementSolver(self.problem, model.thermal),
                self._mechanical_solver(comm, petsc_options, tight, solver_options),
                model.thermal,
            )
        elif model.thermal is not None:  # every step is coupled (model.thermal.is_thermal)
            self.solver = CoupledIncrementSolver(self.problem, model.residual, model.thermal)
        else:
            self.solver = self._mechanical_solver(comm, petsc_options, tight, solver_options)
        # wedges: dolfinx cannot write fields on collapsed hexahedra (its pull-back of their
        # nodes fails at the collapsed edge), the deck's mesh is written with wedge cells (§30.6)
        self.writer: ContactWriter | WedgeDeckWriter | None = None
        xdmf = directory / f"{jobname}.xdmf"
        if model.element_type.name == "C3D15":  # dolfinx 0.11 writes no 18-node prisms (§34)
            pass
        elif deck.wedges.size == 0:
            self.result.xdmf = xdmf
            self.writer = ContactWriter(self.problem, str(xdmf), comm)
        elif model.element_type.name == "C3D8":
            self.result.xdmf = xdmf
            self.writer = WedgeDeckWriter(xdmf, self.values, root=comm.rank == 0)
        self._static_interactions = [pair.interaction for pair in model.pairs]
        self.velocity: dolfinx.fem.Function | None = None  # of *DYNAMIC steps, kept between them
        self.acceleration: dolfinx.fem.Function | None = None
        self.stored_modes: Modes | None = None  # of the last *FREQUENCY, STORAGE=YES step
        self._attempt: tuple | None = None  # (step, increment, attempt, start, dt, step index)
        self._load_time = (0, 0.0)  # (step index, step time) of the current attempt
        self._step_time = 0.0

    def _mechanical_solver(
        self, comm: MPI.Comm, petsc_options: dict | None, tight: bool, solver_options: dict | None
    ) -> ContactNewtonSolver:
        """CalculiX's Newton for the mechanical steps (docs/method.md §7.1)."""
        return ContactNewtonSolver(
            comm,
            self.problem,
            petsc_options=petsc_options,
            check_unpaired=False,
            roundoff_floor=False,
            bounded_scale=False,
            residual_floor=0.0 if tight else CCX_RESIDUAL_FLOOR,
            average_over_step=not tight,
            change_over_iterations=not tight,
            **{"divergence_rule": "ccx", **(solver_options or {})},  # ccx's check (§42)
        )

    def _on_pairing(self, problem: ContactProblem) -> None:
        """Write this pairing's contact elements to the ``.cel`` file (docs/method.md §8.5)."""
        c = self.counters
        if c.attempt == 0:  # the start-of-step pairing of a *DYNAMIC step (no ccx set)
            return
        numbers = (c.step, c.increment, c.attempt, max(problem.iteration, 1))
        if self.files.wants_contact_elements(self.deck.steps[c.step - 1], numbers):
            self.files.write_contact_elements(numbers, self.values.contact_elements(problem))

    # -- steps -------------------------------------------------------------------------------------

    def run(self) -> JobResult:
        """Run every step; raises :class:`JobError` (with the partial result) when one fails."""
        try:
            for index, step in enumerate(self.deck.steps):
                self._run_step(index, step)
            self.result.completed = True
            logger.info("\n Job finished\n")
        except ContactConvergenceError as error:
            self._failed_attempt()
            message = (
                f"step {self.counters.step}, increment {self.counters.increment}, attempt "
                f"{self.counters.attempt}: no convergence: {error}"
            )
            logger.info("\n *ERROR: %s\n", message)
            raise JobError(message, exit_code=2, result=self.result) from error
        finally:
            if self.writer is not None:
                self.writer.close()
            self.files.close()
        return self.result

    def _run_step(self, index: int, step: Step) -> None:
        model, problem = self.model, self.problem
        self.counters = _Counters(step=step.number)
        kind = "Static" if step.dynamic is None and step.modal_dynamic is None else "Dynamic"
        if step.frequency is not None:
            kind = "Frequency"
        if step.coupled is not None:
            kind = "Heat transfer" if step.coupled.heat else "Coupled temperature-displacement"
        logger.info("\n STEP %d\n\n %s analysis was selected\n", step.number, kind)
        # ccx's transient coupled step is dynamic in its mechanics (manual: ALPHA, step loading);
        # a heat transfer step has no mechanics: static increments (docs/method.md §20.9)
        transient = step.coupled is not None and not step.coupled.steady and not step.coupled.heat
        self._set_laws(dynamic=step.dynamic is not None or transient)
        if index > 0:
            bcs = model.begin_step(index)
            problem.set_bcs(bcs)
        if step.coupled is not None:
            model.thermal.begin_step(index, step.coupled.steady)
        self._contact_changes(step)
        self.solver.controls = solver_controls(step, tight=self.tight)
        self.solver.relaxation_iteration = relaxation_iteration(step)
        if step.dynamic is not None or transient:
            self._run_dynamic_step(index, step)
            return
        if step.frequency is not None:
            self._run_frequency_step(index, step)
            return
        if step.modal_dynamic is not None:
            self._run_modal_dynamic_step(index, step)
            return
        static = step.static
        period = static.period
        # thermal steps follow their increments also without contact (ccx 2.20, §39)
        linear = not (step.nlgeom or model.pairs or model.plasticity or step.coupled)
        initial = period if linear else static.initial_increment
        maximum = min(static.maximum if static.maximum is not None else period, period)
        initial = min(initial, maximum)
        # ccx 2.20 raises a missing or smaller minimum to 1e-6 of the period (with a warning)
        minimum = min(max(static.minimum or 0.0, 1e-6 * period), initial)

        self._step_time = 0.0

        def set_load(t: float) -> None:
            self.solver.increment_start = model.u.x.array.copy()
            self._begin_attempt(index, step, t)

        def on_increment(result: IncrementResult) -> None:
            self._end_attempt(index, step, result)

        driver = StaticStep(
            set_load,
            time_points=self._time_points(step),
            period=period,
            initial_increment=initial,
            min_increment=minimum,
            max_increment=maximum,
            fixed=static.direct or linear,
            on_increment=on_increment,
            predictor=self.predictor,
            pair_after_predictor=self.pair_after_predictor,
            guard_predictor=self.guard_predictor,
            elastic_start=bool(model.plasticity),  # ccx's elastic first iteration (§33)
            elastic_contact=self.elastic_contact if model.plasticity else "iterate",  # §33.4
        )
        driver.run(self.solver, model.u)

    def _time_points(self, step: Step) -> np.ndarray | None:
        """The step times the increments must end on: the print requests' ``*TIME POINTS``.

        ccx 2.20 shortens an increment that would pass one (docs/method.md §27).
        """
        names = {p.time_points for p in step.prints if p.time_points is not None}
        if not names:
            return None
        return np.unique(np.concatenate([self.deck.time_points[n].times for n in names]))

    def _set_laws(self, *, dynamic: bool) -> None:
        """ccx's LINEAR law has no tension in ``*DYNAMIC`` steps (docs/method.md §12.3).

        Only the law changes; the friction of earlier ``*CHANGE FRICTION`` cards stays.
        """
        for pair, interaction in zip(self.model.pairs, self._static_interactions):
            law = interaction.law
            if dynamic and isinstance(law, LinearLaw):
                law = law.dynamic()
            if pair.interaction.law is not law:
                pair.interaction = dataclasses.replace(pair.interaction, law=law)

    def _run_dynamic_step(self, index: int, step: Step) -> None:
        """A ``*DYNAMIC`` step: :class:`~dolfinx_ntf.DynamicStep` (docs/method.md §12.4)."""
        from dolfinx_ntf.solvers.dynamics import DynamicStep

        model = self.model
        if self.velocity is None:
            self.velocity = model.initial_velocity()
            if self.problem.elimination is not None:  # dependent dofs (C3D20's face and cell
                # centres, *EQUATION terms) from the nodes' velocities, as the displacement's
                self.problem.elimination.expand(compat.petsc_vector(self.velocity))
                self.velocity.x.scatter_forward()
            self.acceleration = dolfinx.fem.Function(model.V, name="acceleration")
            self.values.velocity = self.velocity
        increments = step.static
        period = increments.period
        maximum = min(increments.maximum or period, period)
        initial = min(increments.initial_increment, maximum)
        # ccx's default minimum: the initial increment or 1e-5 of the period, the smaller
        minimum = min(increments.minimum or min(initial, 1e-5 * period), initial)

        self._step_time = 0.0

        def set_load(t: float) -> None:
            if t > 0.0:
                self._begin_attempt(index, step, t, ramp=False)
            else:
                model.set_time(index, t, ramp=False)  # ccx: full loads from the step start

        def on_increment(result: IncrementResult) -> None:
            self._end_attempt(index, step, result)

        time_points = self._time_points(step)
        driver = DynamicStep(
            model.mass_form(),
            set_load,
            time_points=time_points,
            period=period,
            initial_increment=initial,
            min_increment=minimum,
            max_increment=maximum,
            fixed=increments.direct,
            alpha=step.dynamic.alpha if step.dynamic is not None else step.coupled.alpha,
            velocity=self.velocity,
            acceleration=self.acceleration,
            initial_acceleration_increment=self._start_increment(step, initial, time_points),
            on_increment=on_increment,
        )
        driver.run(self.solver, model.u)

    def _start_increment(
        self, step: Step, initial: float, time_points: np.ndarray | None
    ) -> float | None:
        """The ``initial_acceleration_increment`` of a dynamic step, ccx's or None (exact).

        ccx's initial acceleration is that of an alpha-method increment of a tenth of the first
        increment: the initial one, or shorter if it would pass the first time point
        (docs/method.md §12.7); coupled steps keep the exact one (not measured).
        """
        if self.initial_acceleration != "ccx" or step.dynamic is None:
            return None
        first = initial
        if time_points is not None:
            ahead = time_points[time_points > 1e-9 * step.static.period]
            first = min(first, float(ahead[0])) if ahead.size else first
        from dolfinx_ntf.solvers.dynamics import CCX_START_INCREMENT_FRACTION

        return CCX_START_INCREMENT_FRACTION * first

    def _run_frequency_step(self, index: int, step: Step) -> None:
        """A ``*FREQUENCY`` step: the modes at the current state (docs/method.md §16).

        As ccx 2.20, whose step has no contact elements: the bulk stiffness alone. Each mode's
        sign is fixed by the deck's node order (its first component above 1e-3 of its largest is
        positive), so that serial and parallel runs print the same modes.
        """
        from dolfinx_ntf.solvers.modes import contact_modes

        from .modal_dat import frequency_output

        modes = contact_modes(
            self.problem, self.model.mass_form(), step.frequency.num_eigenvalues, springs=False
        )
        u = self.model.u
        state = u.x.array.copy()
        try:
            shapes = []
            for mode in modes.modes:
                u.x.array[:] = mode.x.array
                shape = self.values.displacements()
                if _first_large(shape) < 0.0:
                    mode.x.array[:] *= -1.0
                    shape = -shape
                shapes.append(shape)
            factors, totals = modes.participation_factors(), modes.total_effective_mass()
            self.files.write_dat_text(frequency_output(modes.eigenvalues, factors, totals))
            if step.prints and step.output_frequency > 0:
                total = self.model.total_time(index, step.static.period)
                for number, shape in enumerate(shapes, 1):
                    self.files.write_mode(step, number, total, shape)
        finally:
            u.x.array[:] = state
            modes.destroy()
        self.result.eigenvalues = modes.eigenvalues
        if step.frequency.storage:
            self.stored_modes = modes

    def _run_modal_dynamic_step(self, index: int, step: Step) -> None:
        """A ``*MODAL DYNAMIC`` step: the stored modes superposed (docs/method.md §25).

        From rest, under the step's concentrated loads in full from its start, with its Rayleigh
        damping, exactly integrated over ccx 2.20's increments. As ccx 2.20 measured on contact5
        and on a longer run of it (§25.4), contact pairs exert no force in the step.
        """
        from dolfinx_ntf.solvers.modal_dynamics import ModalDynamics, RayleighDamping, modal_forces

        from .modal_increments import modal_increments

        if self.stored_modes is None:  # the deck reader requires the earlier step
            raise ValueError(f"{step.location}: no stored modes for the *MODAL DYNAMIC step")
        if self.model.pairs:
            logger.info(
                " *WARNING: contact pairs exert no force in the *MODAL DYNAMIC step at %s (as in "
                "ccx 2.20)",
                step.location,
            )
        damping = None
        if step.modal_damping is not None:
            damping = RayleighDamping(step.modal_damping.alpha, step.modal_damping.beta)
        modes = self.stored_modes
        dynamics = ModalDynamics(modes, damping)
        self.model.set_time(index, step.static.period, ramp=False)  # constant loads
        force = modal_forces(modes, self.model.nodal_loads)
        sizes = modal_increments(
            step.static, variable=step.modal_dynamic.variable, max_increments=step.max_increments
        )
        u = self.model.u
        frequency = step.output_frequency
        for increment, dt in enumerate(sizes, 1):
            dynamics.advance(dt, force, force)
            if frequency > 0 and (increment % frequency == 0 or increment == len(sizes)):
                dynamics.velocity(u)
                velocity = self.values.displacements()
                dynamics.displacement(u)
                displacement = self.values.displacements()
                total = self.model.total_time(index, dynamics.time)
                self.files.write_modal_increment(step, total, displacement, velocity)
        dynamics.displacement(u)

    def _begin_attempt(self, index: int, step: Step, t: float, *, ramp: bool = True) -> None:
        """Count an attempt at step time ``t``, set its loads and open its ``.sta`` row."""
        self._failed_attempt()
        self.counters.attempt += 1
        if self.counters.increment > step.max_increments:
            raise ContactConvergenceError(
                f"the step needs more than INC={step.max_increments} increments ({step.location})"
            )
        c = self.counters
        start = self._step_time
        self._attempt = (step.number, c.increment, c.attempt, start, t - start, index)
        if self.model.thermal is not None:  # each attempt restarts from the last increment's T
            self.model.thermal.begin_increment(t - start, t / step.static.period)
        self.model.set_time(index, t, ramp=ramp)
        values = self.model.constraint_values(index, t)  # reference nodes of *EQUATION
        if values is not None and self.problem.elimination is not None:
            self.problem.elimination.set_values(values)
        self._load_time = (index, t)

    def _end_attempt(self, index: int, step: Step, result: IncrementResult) -> None:
        """Write the converged attempt's ``.sta``/``.cvg`` rows and its printed results."""
        number, increment, attempt, _, size, _ = self._attempt
        self.files.attempt((number, increment, attempt), True, result.iterations,
                           self.model.total_time(index, result.time), result.time, size,
                           self.solver.history)  # fmt: skip
        self._attempt = None
        self._step_time = result.time
        if self.model.thermal is not None:
            self.model.thermal.end_increment()
        self._converged(index, step, result)
        self.counters.increment += 1
        self.counters.attempt = 0

    def _failed_attempt(self) -> None:
        """The ``.sta``/``.cvg`` rows of an attempt that did not converge (times at its start)."""
        if self._attempt is None:
            return
        number, increment, attempt, start, size, index = self._attempt
        history = self.solver.history
        self.files.attempt((number, increment, attempt), False, len(history),
                           self.model.total_time(index, start), start, size, history)  # fmt: skip
        self._attempt = None

    def _contact_changes(self, step: Step) -> None:
        """``*CHANGE FRICTION`` and ``*MODEL CHANGE`` of a step (docs/method.md §11.5)."""
        for change in step.friction_changes:
            friction = friction_of(self.deck, change.friction)
            for pair, spec in zip(self.model.pairs, self.deck.contact_pairs):
                if spec.interaction == change.interaction:
                    pair.interaction = dataclasses.replace(pair.interaction, friction=friction)
        for change in step.model_changes:
            for pair, spec in zip(self.model.pairs, self.deck.contact_pairs):
                if (spec.slave, spec.master) == (change.slave, change.master):
                    pair.active = change.action == "ADD"

    def _converged(self, index: int, step: Step, result: IncrementResult) -> None:
        """Record a converged increment and write the files its output frequency selects."""
        model = self.model
        unpaired = self.problem.unpaired_contacts() if self.problem.states else 0
        if unpaired:
            logger.info(
                " *WARNING: %d slave node(s) penetrate the master without a contact element "
                "(the pairing is frozen after iteration 8, as in ccx)",
                unpaired,
            )
        total = model.total_time(index, result.time)
        meshed = np.zeros(self.deck.node_ids.size, dtype=bool)
        meshed[self.numbering.allgather(self.numbering.owned_rows)[0]] = True
        node_ids = self.deck.node_ids[meshed]
        order = np.argsort(node_ids)
        displacement = self.values.displacements()[meshed]
        contact = self.values.contact_rows(self.files.ccx)
        self.result.increments.append(
            IncrementOutput(
                step=step.number,
                increment=result.increment,
                attempt=result.attempt,
                iterations=result.iterations,
                step_time=result.time,
                time=total,
                node_ids=node_ids[order],
                displacement=displacement[order].copy(),
                contact=contact,
            )
        )
        if self.writer is not None:
            self.writer.write(total)
        frequency = step.output_frequency
        last = result.time_fraction >= 1 - 1e-12
        regular = frequency > 0 and (result.increment % frequency == 0 or last)
        prints = [
            p
            for p in step.prints
            if (regular if p.time_points is None else self._at_time_point(p, step, result.time))
        ]
        if regular or prints:
            self.files.write_increment(
                step,
                result.increment,
                total,
                contact,
                self.values,
                load_time=self._load_time,
                largest_residual=self.solver.largest_residual,
                prints=prints,
                files=regular,
            )

    def _at_time_point(self, request: PrintRequest, step: Step, step_time: float) -> bool:
        """Whether ``step_time`` is one of the request's ``*TIME POINTS`` (docs/method.md §27)."""
        points = self.deck.time_points[request.time_points].times
        return bool(np.any(np.abs(points - step_time) <= 1e-9 * step.static.period))


def _first_large(values: np.ndarray) -> float:
    """The first entry of ``values`` (row-major) above 1e-3 of its largest magnitude."""
    flat = values.ravel()
    return float(flat[np.argmax(np.abs(flat) > 1e-3 * np.abs(flat).max())])


def _read(path: Path, comm: MPI.Comm) -> Deck:
    """The deck at ``path``, read by every process; an error on one is an error on all."""

    def read() -> Deck:
        if not path.is_file():
            raise ValueError(f"deck {path} does not exist")
        if not path.read_text(encoding="latin-1").strip():
            raise ValueError(f"{path}: the deck file is empty")
        deck = read_deck(path)
        if not deck.steps:
            raise ValueError(f"{path}: the deck has no *STEP: nothing to run")
        return deck

    return collectives.collectively(comm, read)


def run_job(
    jobname: str,
    directory: str | Path = ".",
    *,
    comm: MPI.Comm = MPI.COMM_WORLD,
    tight: bool = False,
    progress: bool = True,
    problem_options: dict | None = None,
    petsc_options: dict | None = None,
    predictor: bool = True,
    pair_after_predictor: bool = False,
    guard_predictor: bool = False,
    ccx_format: str = "2.20",
    tangent: str = "ccx",
    line_search: bool = False,
    solver_options: dict | None = None,
    area_weights: str = "ccx",
    initial_acceleration: str = "ccx",
    factorization: str = "auto",
    elastic_contact: str = "start",
) -> JobResult:
    """Run the CalculiX deck ``directory/jobname.inp``; write ``jobname.dat``, ``.cel``, ``.xdmf``.

    Args:
        jobname: Deck name without ``.inp``.
        directory: Directory of the deck; results are written there.
        comm: Communicator; on several processes the files are written by rank 0 and are
            those of the serial run (docs/method.md §14.5).
        tight: Converge every increment to a largest residual of 1e-10 times the average element
            force (ccx's criterion with ``R_n = R_p = 1e-10``) instead of the deck's controls.
        progress: Print ccx-like progress (``log_progress``).
        problem_options: Extra :class:`~dolfinx_ntf.ContactProblem` options (``symmetric``, ...);
            the search is CalculiX's unless ``walk_from_previous_face=True`` (``--stable-pairing``).
            They override those that ``tangent`` sets.
        petsc_options: Linear solver options (default: MUMPS LU).
        predictor: ccx's predictor ``u_n + dt v_prev`` from the second increment of a step (on by
            default, unlike the Python API: see :class:`~dolfinx_ntf.StaticStep`).
        pair_after_predictor: Pair again once the predictor has moved the nodes (beyond ccx, see
            :class:`~dolfinx_ntf.StaticStep`).
        guard_predictor: Start from ``u_n`` instead when the predicted displacement brings slave
            nodes into contact that the increment-start pairing gave no spring (beyond ccx, see
            :class:`~dolfinx_ntf.StaticStep`); False (default) is ccx's predictor everywhere.
        ccx_format: The ccx version whose ``.dat`` and ``.frd`` formats are written, ``"2.20"``
            or ``"2.23"`` (step and increment lines, CELS title, CONTACT records; the values are
            2.20's either way: docs/method.md §13.6).
        tangent: The spring tangent. ``"ccx"`` (default): CalculiX's, symmetrized (without
            friction) and with the interior-projection formula at projections clamped to a face
            edge, so that the iterates follow ccx's (docs/method.md §7.4); ``"exact"``: the exact
            unsymmetric one; ``"auto"``: CalculiX's symmetrized one (exact at clamped
            projections) from ``SYMMETRIC_MIN_DOFS`` dofs on, the exact one below.
        line_search: Line-search the Newton corrections (beyond ccx, the Python API's default:
            :class:`~dolfinx_ntf.ContactNewtonSolver`); off by default, as in ccx.
        solver_options: Extra :class:`~dolfinx_ntf.ContactNewtonSolver` options.
        area_weights: Spring areas of 2D decks: ``"ccx"`` (default: the fixed shares of the faces
            ccx expands 2D edges into, which reproduce its results) or ``"consistent"`` (the
            consistent shares of each edge, rings ``2 pi ∫ r phi_p ds``, which pass the patch
            test; the Python API's default) (``ContactPair.area_weights``, docs/method.md §23.3).
        initial_acceleration: The start of ``*DYNAMIC`` steps: ``"ccx"`` (default: the
            acceleration of an alpha-method increment of a tenth of the initial increment,
            ``(M + beta (1 + alpha) h^2 K) a_0 = f_ext - f(u_0)``, which reproduces ccx's results)
            or ``"exact"`` (``M a_0 = f_ext - f(u_0)``, the Python API's default)
            (``DynamicStep.initial_acceleration_increment``, docs/method.md §12.7).
        factorization: The direct linear solver's factorizations: ``"fresh"``, one per Newton
            iteration (the exact path); ``"reuse"``, GMRES preconditioned by an earlier
            factorization while it converges in a few iterations (the printed values agree to
            the Krylov tolerance, 1e-11 of the residual); ``"auto"`` (default), reuse from
            ``REUSE_MIN_DOFS`` dofs on (docs/method.md §31).
        elastic_contact: The springs in the elastic first iteration of a step (decks with
            ``*PLASTIC``, where that iteration applies; docs/method.md §33.4): ``"start"``
            (default) at the increment start, as ccx 2.20; ``"stick"`` at the first iterate with
            the friction forces stuck; ``"iterate"`` at the first iterate.

    Returns:
        The :class:`JobResult`.

    Raises:
        DeckError: bad deck (message starts with ``file:line``).
        NotImplementedError: a feature that is not supported yet, naming the keyword and line.
        JobError: the analysis stopped (no convergence); files keep the converged increments and
            ``error.result`` holds them.
    """
    if ccx_format not in CCX_FORMATS:
        raise ValueError(f"ccx_format {ccx_format!r}: one of {', '.join(CCX_FORMATS)}")
    if tangent not in TANGENTS:
        raise ValueError(f"tangent {tangent!r}: one of {', '.join(TANGENTS)}")
    if factorization not in FACTORIZATIONS:
        raise ValueError(f"factorization {factorization!r}: one of {', '.join(FACTORIZATIONS)}")
    if initial_acceleration not in INITIAL_ACCELERATIONS:
        raise ValueError(
            f"initial_acceleration {initial_acceleration!r}: one of "
            f"{', '.join(INITIAL_ACCELERATIONS)}"
        )
    start = _time.perf_counter()
    if progress:
        log_progress(details=True)  # ccx's lines: attempts, pairings
    directory = Path(directory)
    path = directory / f"{jobname}.inp"
    deck = _read(path, comm)
    if comm.rank == 0:
        for warning in deck.warnings:
            logger.warning("%s", warning)
    check_requests(deck)
    model = build_model(deck, comm, area_weights=area_weights)
    job = _Job(
        jobname,
        directory,
        model.deck,  # *TIE's ADJUST moved nodes
        model,
        comm,
        tight=tight,
        problem_options={
            "walk_from_previous_face": False,
            "contact_start_slope": False,
            # ccx's tangent, or its symmetrized one on large decks only (docs/method.md §7.4);
            # never with an unsymmetric bulk tangent (finite-strain plasticity, §21.7)
            "symmetric": model.symmetric_bulk
            and (
                tangent == "ccx"
                or (tangent == "auto" and 3 * deck.node_ids.size >= SYMMETRIC_MIN_DOFS)
            ),
            "projection_tangent": "ccx" if tangent == "ccx" else "exact",
            "small_sliding_rule": "last_pair",
            # ccx's friction (docs/method.md §11): stale state, friction in tension, its tangent
            "reset_friction_on_separation": False,
            "friction_in_tension": True,
            "friction_tangent": "ccx",
            **(problem_options or {}),
        },
        petsc_options=petsc_options,
        predictor=predictor,
        pair_after_predictor=pair_after_predictor,
        guard_predictor=guard_predictor,
        ccx_format=ccx_format,
        solver_options={
            "line_search": line_search,
            "factorization": factorization,
            **(solver_options or {}),
        },
        initial_acceleration=initial_acceleration,
        elastic_contact=elastic_contact,
    )
    try:
        return job.run()
    finally:
        job.result.wall_time = _time.perf_counter() - start
