"""Run a CalculiX deck like ``ccx``: read ``JOB.inp``, solve, write ``JOB.dat``/``.cel``/``.xdmf``.

``run_job`` builds the model (``model.py``), runs each ``*STEP`` with
:class:`~dolfinx_ntf.StaticStep` (``*STATIC`` initial increment, period, minimum, maximum;
``DIRECT`` = fixed increments) and writes, per converged increment that the output FREQUENCY
selects:

    - ``JOB.dat``: the ``*NODE PRINT`` (U, RF), ``*EL PRINT`` (S) and ``*CONTACT PRINT`` (CDIS,
      CSTR, CELS, CNUM) blocks in ccx 2.20's exact format and order (docs/method.md §8.5: contact
      rows by pair in deck order, slave nodes ascending). RF is the internal force of the bulk
      elements plus the contact springs at each node, as ccx prints it: the reaction at constrained
      dofs, the applied load elsewhere.
    - ``JOB.cel``: every pairing's contact elements when ``CONTACT ELEMENTS`` is requested
      (docs/method.md §8.5).
    - ``JOB.xdmf``: displacement, contact pressure, clearance and status (every converged
      increment).
    - ``JOB.frd``: the mesh, and the ``*NODE FILE`` (U, RF), ``*EL FILE`` (S) and ``*CONTACT FILE``
      (CDIS, CSTR) results in ccx 2.20's ASCII layout (docs/method.md §13.2).
    - ``JOB.sta`` and ``JOB.cvg``: one row per attempt and per Newton iteration, in ccx's format
      (docs/method.md §13.3).

Newton stops like ccx (manual "Convergence criteria"): the largest residual force component must
fall below ``R_n`` (``*CONTROLS, PARAMETERS=FIELD``, default 0.005) times the average element force,
averaged over the iterations of the increment (``R_p`` after ``I_P`` iterations), and the last
correction must be small against the increment's displacement change (``C_n``), see
:meth:`ContactNewtonSolver.is_converged`. ``tight=True`` replaces the deck's values by
``TIGHT_FIELD_CONTROLS`` (``R_n = R_p = 1e-10``), so that converged solutions are compared.

Steps without contact pairs and without NLGEOM are linear: one increment over the whole step, as in
ccx.

Under ``mpirun -n N`` the model is distributed by dolfinx and every output is gathered in ccx
numbering (``gather.py``) and written by rank 0: the files are those of the serial run
(docs/method.md §14.5, §14.9, §14.10).
"""

from __future__ import annotations

import logging
import time as _time
from dataclasses import dataclass, field
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.kernels.friction import output_tangents
from dolfinx_ntf.kernels.laws import LinearLaw, SurfaceInteraction
from dolfinx_ntf.logs import log_progress
from dolfinx_ntf.outputs.results import ContactWriter, contact_results
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.solvers.convergence import TIGHT_FIELD_CONTROLS
from dolfinx_ntf.solvers.dynamics import DynamicStep
from dolfinx_ntf.solvers.errors import ContactConvergenceError
from dolfinx_ntf.solvers.newton import ContactNewtonSolver
from dolfinx_ntf.solvers.steps import IncrementResult, StaticStep

from .cel import ContactElementsFile
from .dat import DatBlock, contact_print_blocks, el_print_blocks, node_print_blocks, write_dat
from .deck import Deck, PrintRequest, Step, read_deck
from .frd import FrdBlock, FrdWriter
from .gather import CcxNumbering, Discard
from .model import CalculixModel, build_model, friction_of
from .progress import CvgFile, StaFile
from .roundoff import (
    FieldAccuracy,
    clean,
    clean_contact,
    clean_dat_blocks,
    clean_frd_block,
    clean_totals,
    element_sizes,
    force_floor,
    largest_modulus,
    law_accuracy,
    zero_below,
)

__all__ = ["ContactRows", "IncrementOutput", "JobError", "JobResult", "run_job"]

logger = logging.getLogger("dolfinx_ntf")

#: CalculiX 2.20 counts a largest residual force below this (in the deck's force unit) as zero
#: in its convergence test (measured, docs/method.md §7.1); not with ``tight=True``.
CCX_RESIDUAL_FLOOR = 1e-6

#: From this many dofs on the deck runner uses CalculiX's symmetrized contact tangent, whose
#: Cholesky factorization costs about half an LU; below, the exact tangent, which converges in fewer
#: iterations where projections are clamped to a face edge (docs/method.md §7.4).
SYMMETRIC_MIN_DOFS = 10_000


class JobError(RuntimeError):
    """A job that stopped early (e.g. no convergence); files keep the converged increments.

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
class ContactRows:
    """Contact elements of one pair at one increment, slave nodes ascending (the ``.dat`` rows).

    Attributes:
        pair: ``SLAVE-MASTER`` surface names.
        nodes: ``(k,)`` ccx slave node numbers.
        clearance: ``(k,)`` CDIS normal value (negative = penetration).
        pressure: ``(k,)`` CSTR contact pressure.
        energy: ``(k,)`` CELS spring energy (with ccx 2.20's friction energy, docs/method.md
            §11.4).
        master_faces: ``(k, n)`` ccx node numbers of each element's master face, ccx face order.
        slip: ``(k, 2)`` CDIS tangential columns: accumulated tangential relative displacement
            along ccx's output directions t1, t2 (zero without friction).
        shear: ``(k, 2)`` CSTR tangential columns: shear traction along t1, t2.
        accuracy: ``(length, pressure (k,), energy (k,))``: what each value is known to
            (``roundoff.clean_contact``, docs/method.md §14.5).
    """

    pair: str
    nodes: np.ndarray
    clearance: np.ndarray
    pressure: np.ndarray
    energy: np.ndarray
    master_faces: np.ndarray
    slip: np.ndarray | None = None
    shear: np.ndarray | None = None
    accuracy: tuple | None = None


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

    def displacement_of(self, node_ids) -> np.ndarray:
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
        dat, cel, xdmf: Files written (``cel`` is None without CONTACT ELEMENTS).
        completed: True if every step ran to its end.
        wall_time: Seconds spent in ``run_job``.
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
    """State of one run (the model, problem, solver, writers and counters)."""

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
    ) -> None:
        self.deck, self.model, self.comm, self.tight = deck, model, comm, tight
        self.predictor = predictor
        self.guard_predictor = guard_predictor
        self.pair_after_predictor = pair_after_predictor
        self.result = JobResult(jobname, directory, model)
        self.result.dat = directory / f"{jobname}.dat"
        self.root = comm.rank == 0  # writes the files (docs/method.md §14.5)
        if self.root:
            write_dat(self.result.dat, [])
        self.cel: ContactElementsFile | None = None
        cel = directory / f"{jobname}.cel"
        if any(step.contact_elements for step in deck.steps):
            self.result.cel = cel
            self.cel = ContactElementsFile(cel, deck.num_elements) if self.root else Discard()
        elif cel.exists() and self.root:  # ccx deletes the file at program start
            cel.unlink()
        self.counters = _Counters()
        self._cel_overflow = False

        v = ufl.TestFunction(model.V)
        internal = ufl.inner(model.first_piola, ufl.grad(v)) * model.dx
        self.problem = model.create_problem(
            model.begin_step(0), element_forces=internal, **problem_options
        )
        self.problem.pairing_callbacks.append(self._on_pairing)
        self.numbering = CcxNumbering(model, internal)
        self._stress = None
        self.solver = ContactNewtonSolver(
            comm,
            self.problem,
            petsc_options=petsc_options,
            check_unpaired=False,
            residual_floor=0.0 if tight else CCX_RESIDUAL_FLOOR,
            average_over_step=not tight,
            change_over_iterations=not tight,
        )
        self.result.xdmf = directory / f"{jobname}.xdmf"
        self.writer = ContactWriter(self.problem, str(self.result.xdmf), comm)
        self._static_interactions = [pair.interaction for pair in model.pairs]
        self.velocity: dolfinx.fem.Function | None = None  # of *DYNAMIC steps, kept between them
        self.acceleration: dolfinx.fem.Function | None = None
        self.result.frd = directory / f"{jobname}.frd"
        self.frd = _frd_writer(self.result.frd, deck, model) if self.root else Discard()
        self.sta = StaFile(directory / f"{jobname}.sta") if self.root else Discard()
        self.cvg = CvgFile(directory / f"{jobname}.cvg") if self.root else Discard()
        self._attempt: tuple | None = None  # (step, increment, attempt, total, step time, dt)
        self._load_time = (0, 0.0)  # (step index, step time) of the current attempt
        self._step_time = 0.0
        self._field_scales: tuple[float, float, tuple[float, float]] | None = None

    # -- forces ------------------------------------------------------------------------------------

    def internal_forces(self) -> np.ndarray:
        """``(N, 3)`` internal force of bulk elements plus contact springs at every deck node.

        Summed in ccx order, the same on any number of processes; C3D20's face- and cell-centre
        forces moved to its 20 nodes (docs/method.md §13.5). Collective.
        """
        return self.numbering.nodal_forces(self.problem)

    def printed_forces(self) -> tuple[np.ndarray, float]:
        """:meth:`internal_forces` with those within their accuracy as 0, and that accuracy.

        The accuracy is the converged iterate's largest residual force plus round-off, plus the
        round-off of the displacement they come from (docs/method.md §14.5). Collective.
        """
        forces = self.internal_forces()
        floor = force_floor(forces, getattr(self.solver, "largest_residual", 0.0))
        floor += self.field_accuracy().force
        return clean(forces, floor), floor

    def field_accuracy(self) -> FieldAccuracy:
        """Accuracy of the stresses and contact values of the current displacement.

        From the largest coordinate and displacement, the largest modulus and the smallest
        element (docs/method.md §14.5). Collective.
        """
        if self._field_scales is None:
            deck = self.deck
            block = deck.elements[self.model.element_type.name]
            coords = np.asarray(deck.node_coords, dtype=np.float64)
            self._field_scales = (
                float(np.abs(coords).max(initial=0.0)),
                largest_modulus(m.elastic for m in deck.materials.values() if m.elastic),
                element_sizes(coords, deck.node_index(block.connectivity)),
            )
        coordinates, modulus, sizes = self._field_scales
        local = float(np.abs(self.model.u.x.array).max(initial=0.0))
        return FieldAccuracy.of(coordinates, self.comm.allreduce(local, MPI.MAX), modulus, sizes)

    def stresses(self, element_ids: np.ndarray) -> np.ndarray:
        """Cauchy stresses ``(E, q, 6)`` (xx, yy, zz, xy, xz, yz) at ccx's integration points.

        Collective: each element is evaluated by the process owning it.
        """
        if self._stress is None:
            points = self.model.element_type.integration_points
            self._stress = (dolfinx.fem.Expression(self.model.cauchy, points), points.shape[0])
        expression, q = self._stress
        index = ([0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2])

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(
                expression, self.model.mesh, cells.astype(np.int32)
            ).reshape(cells.size, q, 3, 3)
            return values[:, :, index[0], index[1]]

        return self.numbering.element_values(element_ids, evaluate, (q, 6))

    # -- contact -----------------------------------------------------------------------------------

    def contact_rows(self) -> list[ContactRows]:
        """Contact rows of every pair at the current springs, slave nodes ascending.

        Collective: the springs of all processes.
        """
        rows = []
        numbering = self.numbering
        length = self.field_accuracy().length
        for state, results, pair in zip(
            self.problem.states, contact_results(self.problem), self.deck.contact_pairs
        ):
            faces = numbering.ccx_nodes(self.problem, state.master_faces.faces[state.spring_face])
            t1, t2 = output_tangents(results.normal)
            slip = np.column_stack([np.einsum("ni,ni->n", results.slip, t) for t in (t1, t2)])
            shear = np.column_stack([np.einsum("ni,ni->n", results.shear, t) for t in (t1, t2)])
            # ccx 2.20 prints twice the tangential spring energy (docs/method.md §11.4)
            energy = results.energy + 2.0 * results.friction_energy
            dp, de = law_accuracy(
                state.pair.interaction.law, -results.clearance, results.area, length
            )
            nodes, clearance, pressure, energy, faces, slip, shear, dp, de = numbering.allgather(
                numbering.ccx_nodes(self.problem, results.node),
                results.clearance,
                results.pressure,
                energy,
                faces,
                slip.reshape(-1, 2),
                shear.reshape(-1, 2),
                dp,
                de,
            )
            faces = numbering.master_faces(pair.master, faces)
            order = np.argsort(nodes, kind="stable")
            rows.append(
                ContactRows(
                    results.pair,
                    nodes[order],
                    clearance[order],
                    pressure[order],
                    energy[order],
                    faces[order],
                    slip[order],
                    shear[order],
                    (length, dp[order], de[order]),
                )
            )
        return rows

    def _on_pairing(self, problem: ContactProblem) -> None:
        """Write this pairing's contact elements to the ``.cel`` file (docs/method.md §8.5)."""
        step = self.deck.steps[self.counters.step - 1]
        if self.cel is None or not step.contact_elements or self._cel_overflow:
            return
        if self.counters.attempt == 0:  # the start-of-step pairing of a *DYNAMIC step (no ccx set)
            return
        numbers = (
            self.counters.step,
            self.counters.increment,
            self.counters.attempt,
            max(problem.iteration, 1),
        )
        if max(numbers) > 999:
            logger.warning(
                " *WARNING: contact element set numbers above 999 (ccx limit): no more .cel output"
            )
            self._cel_overflow = True
            return
        numbering = self.numbering
        for state, pair in zip(problem.states, self.deck.contact_pairs):
            slaves, faces = numbering.allgather(
                numbering.ccx_nodes(problem, state.slave.nodes[state.spring_slave]),
                numbering.ccx_nodes(problem, state.master_faces.faces[state.spring_face]),
            )
            faces = numbering.master_faces(pair.master, faces)
            order = np.argsort(slaves, kind="stable")
            step_, increment, attempt, iteration = numbers
            self.cel.write(
                faces[order],
                slaves[order],
                step=step_,
                increment=increment,
                attempt=attempt,
                iteration=iteration,
            )

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
            self.writer.close()
            self.frd.close()
        return self.result

    def _run_step(self, index: int, step: Step) -> None:
        model, problem = self.model, self.problem
        self.counters = _Counters(step=step.number)
        kind = "Static" if step.dynamic is None else "Dynamic"
        logger.info("\n STEP %d\n\n %s analysis was selected\n", step.number, kind)
        self._set_laws(dynamic=step.dynamic is not None)
        if index > 0:
            bcs = model.begin_step(index)
            problem.set_bcs(bcs)
        self._contact_changes(step)
        controls = step.field_controls()
        self.solver.controls = {
            k: float(v)
            for k, v in (TIGHT_FIELD_CONTROLS if self.tight else controls).items()
            if v is not None
        }
        timing = [v for line in step.controls.get("TIMEINCREMENTATION", ()) for v in line]
        self.solver.relaxation_iteration = (
            int(timing[2]) if len(timing) > 2 and timing[2] is not None else 9
        )

        if step.dynamic is not None:
            self._run_dynamic_step(index, step)
            return
        static = step.static
        period = static.period
        linear = not step.nlgeom and not model.pairs
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
            period=period,
            initial_increment=initial,
            min_increment=minimum,
            max_increment=maximum,
            fixed=static.direct or linear,
            on_increment=on_increment,
            predictor=self.predictor,
            pair_after_predictor=self.pair_after_predictor,
            guard_predictor=self.guard_predictor,
        )
        driver.run(self.solver, model.u)

    def _set_laws(self, *, dynamic: bool) -> None:
        """ccx's LINEAR law has no tension in ``*DYNAMIC`` steps (docs/method.md §12.3).

        Only the law changes; the friction of earlier ``*CHANGE FRICTION`` cards stays.
        """
        for pair, interaction in zip(self.model.pairs, self._static_interactions):
            law = interaction.law
            if dynamic and isinstance(law, LinearLaw):
                law = law.dynamic()
            if pair.interaction.law is not law:
                pair.interaction = SurfaceInteraction(law, pair.interaction.friction)

    def _run_dynamic_step(self, index: int, step: Step) -> None:
        """A ``*DYNAMIC`` step: :class:`~dolfinx_ntf.DynamicStep` (docs/method.md §12.4)."""
        model = self.model
        if self.velocity is None:
            self.velocity = _initial_velocity(self.deck, model)
            self.acceleration = dolfinx.fem.Function(model.V, name="acceleration")
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

        driver = DynamicStep(
            _mass_form(self.deck, model),
            set_load,
            period=period,
            initial_increment=initial,
            min_increment=minimum,
            max_increment=maximum,
            fixed=increments.direct,
            alpha=step.dynamic.alpha,
            velocity=self.velocity,
            acceleration=self.acceleration,
            on_increment=on_increment,
        )
        driver.run(self.solver, model.u)

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
        self.model.set_time(index, t, ramp=ramp)
        values = self.model.constraint_values(index, t)  # reference nodes of *EQUATION
        if values is not None and self.problem.elimination is not None:
            self.problem.elimination.set_values(values)
        self._load_time = (index, t)

    def _end_attempt(self, index: int, step: Step, result: IncrementResult) -> None:
        """Write the converged attempt's ``.sta``/``.cvg`` rows and its printed results."""
        number, increment, attempt, _, size, _ = self._attempt
        self.sta.row(number, increment, attempt, True, result.iterations,
                     self.model.total_time(index, result.time), result.time, size)  # fmt: skip
        self.cvg.rows(number, increment, attempt, self.solver.history)
        self._attempt = None
        self._step_time = result.time
        self._converged(index, step, result)
        self.counters.increment += 1
        self.counters.attempt = 0

    def _failed_attempt(self) -> None:
        """The ``.sta``/``.cvg`` rows of an attempt that did not converge (times at its start)."""
        if self._attempt is None:
            return
        number, increment, attempt, start, size, index = self._attempt
        history = self.solver.history
        self.sta.row(number, increment, attempt, False, len(history),
                     self.model.total_time(index, start), start, size)  # fmt: skip
        self.cvg.rows(number, increment, attempt, history)
        self._attempt = None

    def _contact_changes(self, step: Step) -> None:
        """``*CHANGE FRICTION`` and ``*MODEL CHANGE`` of a step (docs/method.md §11.5)."""
        for change in step.friction_changes:
            friction = friction_of(self.deck, change.friction)
            for pair, spec in zip(self.model.pairs, self.deck.contact_pairs):
                if spec.interaction == change.interaction:
                    pair.interaction = SurfaceInteraction(pair.interaction.law, friction)
        for change in step.model_changes:
            for pair, spec in zip(self.model.pairs, self.deck.contact_pairs):
                if (spec.slave, spec.master) == (change.slave, change.master):
                    pair.active = change.action == "ADD"

    def _converged(self, index: int, step: Step, result: IncrementResult) -> None:
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
        displacement = self.numbering.nodal(model.u.x.array.reshape(-1, 3))[meshed]
        contact = self.contact_rows()
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
        self.writer.write(total)
        frequency = step.output_frequency
        last = result.time_fraction >= 1 - 1e-12
        if frequency > 0 and (result.increment % frequency == 0 or last):
            contact = [clean_contact(rows) for rows in contact]  # printed values (§14.5)
            blocks = self._blocks(step, total, contact)
            if self.root:
                write_dat(self.result.dat, clean_dat_blocks(blocks), append=True)
            for block in self._frd_blocks(step, result.increment, total, contact):
                self.frd.write(clean_frd_block(block))

    def _frd_blocks(
        self, step: Step, increment: int, total: float, contact: list[ContactRows]
    ) -> list[FrdBlock]:
        """The ``.frd`` blocks of the file requests, in ccx's order: DISP, STRESS, FORC, CONTACT."""
        keys = {(r.kind, k): r for r in step.file_requests for k in r.keys}
        blocks = []

        def node_block(name: str, request, values: np.ndarray) -> None:
            ids = self.deck.node_ids
            if request.set is not None:  # in set order, repeats kept, as ccx (docs/method.md §13.2)
                ids = self.deck.nsets[request.set]
            values = values[self.deck.node_index(ids)]
            if name == "DISP":
                values = self._with_reference(ids, values)
            blocks.append(FrdBlock(name, (), step.number, increment, total, ids, values))

        if ("NODE", "U") in keys:
            node_block(
                "DISP", keys["NODE", "U"], self.numbering.nodal(self.model.u.x.array.reshape(-1, 3))
            )
        if ("EL", "S") in keys:
            nodes, values = self.nodal_stresses()
            values = zero_below(values, self.field_accuracy().stress)
            if keys["EL", "S"].set is not None:  # its nodes that have a stress, in set order
                members = self.deck.nsets[keys["EL", "S"].set]
                pos = np.minimum(np.searchsorted(nodes, members), nodes.size - 1)
                keep = nodes[pos] == members
                nodes, values = members[keep], values[pos[keep]]
            blocks.append(FrdBlock("STRESS", (), step.number, increment, total, nodes, values))
        if ("NODE", "RF") in keys:
            node_block("FORC", keys["NODE", "RF"], self.printed_forces()[0])
        if ("CONTACT", "CDIS") in keys or ("CONTACT", "CSTR") in keys:
            nodes = np.concatenate([r.nodes for r in contact]) if contact else np.zeros(0, int)
            values = np.zeros((nodes.size, 6))
            if contact:
                values[:, 0] = np.concatenate([r.clearance for r in contact])
                values[:, 3] = np.concatenate([r.pressure for r in contact])
            # ccx writes the contact elements in reverse order here (ascending in the .dat file)
            blocks.append(
                FrdBlock("CONTACT", (), step.number, increment, total, nodes[::-1], values[::-1])
            )
        return blocks

    def _with_reference(self, ids: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``values (n, 3)`` of nodes ``ids``, reference nodes at their prescribed displacement."""
        gathered = None  # free reference nodes: from the displacement of all processes
        if self.model.free_references:
            gathered = self.numbering.nodal(self.model.u.x.array.reshape(-1, 3))
        keys, known = self.model.reference_displacements(*self._load_time, gathered)
        if keys.size == 0:
            return values
        wanted = 3 * self.deck.node_index(ids)[:, None] + np.arange(3)
        pos = np.minimum(np.searchsorted(keys, wanted), keys.size - 1)
        hit = keys[pos] == wanted
        values = values.copy()
        values[hit] = known[pos[hit]]
        return values

    def nodal_stresses(self) -> tuple[np.ndarray, np.ndarray]:
        """Cauchy stresses at the nodes like ccx's ``.frd`` (frd order xx, yy, zz, xy, yz, zx).

        Integration-point values extrapolated to each element's nodes, averaged over the elements
        around a node (docs/method.md §13.2).
        """
        block = self.deck.elements[self.model.element_type.name]
        extrapolate = self.model.element_type.extrapolation
        at_nodes = np.einsum("nq,eqk->enk", extrapolate, self.stresses(block.ids))
        index = self.deck.node_index(block.connectivity)
        total = np.zeros((self.deck.node_ids.size, 6))
        count = np.zeros(self.deck.node_ids.size)
        np.add.at(total, index, at_nodes)
        np.add.at(count, index, 1.0)
        used = count > 0
        values = total[used] / count[used, None]
        return self.deck.node_ids[used], values[:, [0, 1, 2, 3, 5, 4]]

    def _blocks(self, step: Step, total: float, contact: list[ContactRows]) -> list[DatBlock]:
        blocks: list[DatBlock] = []
        forces, floor = None, 0.0
        displacement = self.numbering.nodal(self.model.u.x.array.reshape(-1, 3))
        for request in step.prints:
            if request.kind == "NODE":
                ids = self.deck.nsets[request.set]
                for key in request.keys:
                    if key == "RF" and forces is None:
                        forces, floor = self.printed_forces()
                    values = (displacement if key == "U" else forces)[self.deck.node_index(ids)]
                    if key == "U":
                        values = self._with_reference(ids, values)
                    new = node_print_blocks(
                        key, request.set, total, ids, values, totals=request.totals
                    )
                    blocks += clean_totals(new, ids.size, floor) if key == "RF" else new
            elif request.kind == "EL":
                blocks += self._element_blocks(request, total)
            else:
                blocks += self._contact_blocks(request, total, contact)
        return blocks

    def _element_blocks(self, request: PrintRequest, total: float) -> list[DatBlock]:
        ids = self.deck.elsets[request.set]
        blocks = []
        for key in request.keys:
            if key != "S":
                raise NotImplementedError(
                    f"{request.location}: *EL PRINT key {key} is not supported yet"
                )
            stresses = zero_below(self.stresses(ids), self.field_accuracy().stress)
            blocks += el_print_blocks("S", request.set, total, ids, stresses)
        return blocks

    @staticmethod
    def _contact_blocks(
        request: PrintRequest, total: float, contact: list[ContactRows]
    ) -> list[DatBlock]:
        nodes = np.concatenate([r.nodes for r in contact]) if contact else np.zeros(0, np.int64)
        zeros = np.zeros(nodes.size)
        zeros2 = np.zeros((nodes.size, 2))

        def tangential(name: str) -> np.ndarray:
            return np.concatenate([getattr(r, name) for r in contact]) if contact else zeros2

        columns = {
            "CDIS": lambda: np.column_stack(
                [
                    np.concatenate([r.clearance for r in contact]) if contact else zeros,
                    tangential("slip"),
                ]
            ),
            "CSTR": lambda: np.column_stack(
                [
                    np.concatenate([r.pressure for r in contact]) if contact else zeros,
                    tangential("shear"),
                ]
            ),
            "CELS": lambda: np.concatenate([r.energy for r in contact]) if contact else zeros,
            "CNUM": lambda: None,
        }
        blocks = []
        for key in request.keys:
            if key not in columns:
                raise NotImplementedError(
                    f"{request.location}: *CONTACT PRINT key {key} is not supported yet"
                )
            blocks += contact_print_blocks(key, total, nodes, columns[key](), totals=request.totals)
        return blocks


def _mass_form(deck: Deck, model: CalculixModel) -> ufl.Form:
    """``rho inner(w, v) dx`` with the ``*DENSITY`` of each section's material (ccx quadrature)."""
    Q = compat.scalar_space(model.mesh, "DG", 0)
    rho = dolfinx.fem.Function(Q, name="density")
    block_ids = deck.elements[model.element_type.name].ids
    for section in deck.sections:
        density = deck.materials[section.material].extra.get("*DENSITY")
        if not density or len(density) != 1 or density[0][0] is None or density[0][0] <= 0.0:
            raise ValueError(
                f"{section.location}: a *DYNAMIC step needs one positive *DENSITY in material "
                f"{section.material} (temperature-dependent densities are not supported)"
            )
        members = np.unique(deck.elsets[section.elset])
        cells = model.element_cells(members[np.isin(members, block_ids)])
        cells = cells[cells >= 0]  # this process's (owned and ghost) cells
        rho.x.array[compat.cell_dofs(Q)[cells, 0]] = density[0][0]
    w, v = ufl.TrialFunction(model.V), ufl.TestFunction(model.V)
    return rho * ufl.inner(w, v) * ufl.dx(domain=model.mesh)  # consistent mass, exact


def _initial_velocity(deck: Deck, model: CalculixModel) -> dolfinx.fem.Function:
    """The ``*INITIAL CONDITIONS, TYPE=VELOCITY`` of the deck as a Function (zero elsewhere)."""
    velocity = dolfinx.fem.Function(model.V, name="velocity")
    values = velocity.x.array.reshape(-1, 3)
    for condition in deck.initial_velocities:
        dofs = model.node_dofs(condition.nodes)
        values[dofs[dofs >= 0], condition.dof - 1] = condition.value
    velocity.x.scatter_forward()
    return velocity


def _frd_writer(path: Path, deck: Deck, model: CalculixModel) -> FrdWriter:
    """The ``.frd`` file with the deck's mesh (ccx writes it for every job)."""
    block = deck.elements[model.element_type.name]
    materials = list(deck.materials)
    index = dict(zip(materials, range(1, len(materials) + 1)))
    element_material = np.zeros(block.ids.size, dtype=np.int64)
    position = {int(e): k for k, e in enumerate(block.ids)}
    for section in deck.sections:
        for element in deck.elsets[section.elset]:
            element_material[position[int(element)]] = index[section.material]
    return FrdWriter(
        path,
        deck.node_ids,
        deck.node_coords,
        block.ids,
        model.element_type.name,
        block.connectivity,
        element_material,
        materials + list(deck.interactions),
    )


def _check_requests(deck: Deck) -> None:
    """Output keys this runner cannot produce: a clear error before anything runs."""
    supported = {"NODE": {"U", "RF"}, "EL": {"S"}, "CONTACT": {"CDIS", "CSTR", "CELS", "CNUM"}}
    for step in deck.steps:
        for request in step.prints:
            for key in request.keys:
                if key not in supported[request.kind]:
                    raise NotImplementedError(
                        f"{request.location}: *{request.kind} PRINT key {key} is not supported yet"
                    )
    written = {"NODE": {"U", "RF"}, "EL": {"S"}, "CONTACT": {"CDIS", "CSTR"}}
    for step in deck.steps:
        for request in step.file_requests:
            for key in request.keys:
                if key not in written[request.kind]:
                    logger.warning(
                        " *WARNING: %s key %s is not written to the .frd file (%s)",
                        request.keyword,
                        key,
                        request.location,
                    )


def _read(path: Path, comm: MPI.Comm) -> Deck:
    """The deck at ``path``, read by every process; an error on one is an error on all."""

    def read() -> Deck:
        if not path.is_file():
            raise ValueError(f"deck {path} does not exist")
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
    guard_predictor: bool = True,
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
            the search is CalculiX's unless ``walk_from_previous_face=True`` (``--stable-pairing``);
            the tangent is CalculiX's symmetrized one from :data:`SYMMETRIC_MIN_DOFS` dofs on,
            the exact one below, unless ``symmetric`` says otherwise (docs/method.md §7.4).
        petsc_options: Linear solver options (default: MUMPS LU).
        predictor: ccx's predictor ``u_n + dt v_prev`` from the second increment of a step (on by
            default, unlike the Python API: see :class:`~dolfinx_ntf.StaticStep`).
        pair_after_predictor: Pair again once the predictor has moved the nodes (beyond ccx, see
            :class:`~dolfinx_ntf.StaticStep`).
        guard_predictor: Start from ``u_n`` instead when the predicted displacement brings slave
            nodes into contact that the increment-start pairing gave no spring (beyond ccx, see
            :class:`~dolfinx_ntf.StaticStep`); False is ccx's predictor everywhere.

    Returns:
        The :class:`JobResult`.

    Raises:
        DeckError: bad deck (message starts with ``file:line``).
        NotImplementedError: a feature that is not supported yet, naming the keyword and line.
        JobError: the analysis stopped (no convergence); files keep the converged increments and
            ``error.result`` holds them.
    """
    start = _time.perf_counter()
    if progress:
        log_progress()
    directory = Path(directory)
    path = directory / f"{jobname}.inp"
    deck = _read(path, comm)
    if comm.rank == 0:
        for warning in deck.warnings:
            logger.warning("%s", warning)
    _check_requests(deck)
    model = build_model(deck, comm)
    job = _Job(
        jobname,
        directory,
        deck,
        model,
        comm,
        tight=tight,
        problem_options={
            "walk_from_previous_face": False,
            "contact_start_slope": False,
            # ccx's symmetrized tangent on large decks: Cholesky instead of LU (docs/method.md §7.4)
            "symmetric": 3 * deck.node_ids.size >= SYMMETRIC_MIN_DOFS,
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
    )
    try:
        return job.run()
    finally:
        job.result.wall_time = _time.perf_counter() - start
