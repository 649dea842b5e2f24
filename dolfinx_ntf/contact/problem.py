"""The nonlinear problem that adds contact springs to dolfinx's residual: :class:`ContactProblem`.

:class:`ContactProblem` has the shape of dolfinx's ``NonlinearProblem`` (compiled forms ``a`` and
``L``, callbacks ``form``, ``F``, ``J``: the
:class:`~dolfinx_ntf.solvers.newton_loop.NonlinearSystem` role) without depending on its
version-specific class. Its callbacks, besides assembling the user's UFL forms, (re-)pair slave
nodes with master faces on CalculiX's schedule (docs/method.md §3.1) and add the spring elements
(docs/method.md §5, §6). The pairing itself (pair states, halo, search, ADJUST, friction anchors) is
its :class:`~dolfinx_ntf.contact.pairing.Pairing`; the problem keeps the forms, the matrix, the
constraint elimination and the callbacks. The step driver in ``solvers/`` tells it when steps and
increments start.
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.adjust import follow_geometric_rows
from dolfinx_ntf.contact.assembly import ContactAssembler, SpringBlocks
from dolfinx_ntf.contact.evaluation import area_block, evaluate_pair
from dolfinx_ntf.contact.pair import ContactPair, PairState
from dolfinx_ntf.contact.pairing import Pairing
from dolfinx_ntf.contact.velocity import NodeVelocity
from dolfinx_ntf.fem import serendipity, serendipity_quad, serendipity_wedge
from dolfinx_ntf.fem.bulk_jacobian import BulkJacobian
from dolfinx_ntf.fem.constraints import (
    ConstraintElimination,
    LinearConstraint,
    LinearConstraintBlock,
)
from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.kernels.friction import TANGENT_MODES
from dolfinx_ntf.kernels.start_slope import start_law
from dolfinx_ntf.logs import details_logger
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.parallel.global_constraints import distributed_elimination
from dolfinx_ntf.parallel.halo import NodeHalo

__all__ = [
    "ContactPair",
    "ContactProblem",
    "ElementTerm",
    "MaterialHistory",
    "PairState",
    "ResidualTerm",
]

logger = logging.getLogger("dolfinx_ntf")

#: A change of the prescribed displacements above which ccx's first iteration is elastic (§33).
_ELASTIC_START_CHANGE = 1e-5

#: Where the springs of CalculiX's elastic first iterate are evaluated (docs/method.md §33.4).
ELASTIC_CONTACT = ("iterate", "start", "stick")

#: Re-pairing happens at the start of iterations 2..LAST_REPAIRING_ITERATION
#: (docs/method.md §3.1, ccx: iit <= 8).
LAST_REPAIRING_ITERATION = 8


class ResidualTerm(typing.Protocol):
    """A term added to the residual and the Jacobian after the bulk form and the springs.

    For example the inertia of a dynamic step (docs/method.md §12); see
    :attr:`~dolfinx_ntf.ContactProblem.extra_terms`.
    """

    def add_to_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Add the term's residual at ``x`` to ``b``."""

    def add_to_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Add the term's Jacobian at ``x`` to the assembled ``A``."""

    def force_sum(self) -> tuple[float, int]:
        """Sum of the absolute values of its nodal forces and their count (owned entries).

        Enters :meth:`~dolfinx_ntf.ContactProblem.average_element_force`.
        """


class ElementTerm(typing.Protocol):
    """Elements between nodes that may share no cell, in the global numbering.

    For example discrete springs (:class:`~dolfinx_ntf.DiscreteSprings`, docs/method.md §18); see
    :attr:`~dolfinx_ntf.ContactProblem.element_terms`. The problem reserves the term's couplings
    in the matrix pattern and assembles its blocks with the contact springs. Collective methods.
    """

    def node_couplings(self) -> np.ndarray:
        """(K, 2) global node pairs whose matrix entries this process adds."""

    def evaluate(
        self, x: PETSc.Vec, bcs: typing.Sequence[compat.DirichletBC], *, tangent: bool = True
    ) -> GlobalBlocks:
        """This process's blocks at ``x``; dofs of ``bcs`` get index -1."""

    def force_sum(self) -> tuple[float, int]:
        """Sum of the absolute values of its nodal forces and their count (this process's)."""


class MaterialHistory(typing.Protocol):
    """A material state at the quadrature points that the increments carry (e.g. plastic strains).

    For example :class:`~dolfinx_ntf.J2Plasticity` (docs/method.md §21); see
    :attr:`~dolfinx_ntf.ContactProblem.history`. The problem evaluates it at every iterate before
    the residual; the step driver commits it when an increment converges (with the friction state)
    and rolls it back when an attempt fails. Collective methods.
    """

    def evaluate(self) -> None:
        """Update the stress and tangent at the current displacement from the committed state."""

    def evaluate_elastic(self) -> None:
        """Like :meth:`evaluate`, elastically: the trial state without return map (§33)."""

    def increment_converged(self) -> None:
        """Commit the state of the current (converged) displacement."""

    def increment_rejected(self) -> None:
        """Forget the trial state: the displacement is back at the increment start."""


class ContactProblem:
    """Nonlinear problem ``F(u) + f_contact(u) = 0`` with node-to-face penalty springs.

    Args:
        F: The user's UFL residual (any bulk law: small strain, St.Venant-Kirchhoff,
            neo-Hookean...).
        u: The displacement, a 3D vector Lagrange function (P1 or P2).
        pairs: Contact pairs (none gives a plain nonlinear problem with the same driver and
            outputs).
        bcs: Dirichlet conditions.
        J: UFL Jacobian (derived from ``F`` when omitted).
        symmetric: Symmetrize the spring matrices like CalculiX's frictionless contact; default is
            the consistent (unsymmetric) tangent.
        linearize_area: Recompute spring areas at every evaluation and include their derivative in
            the tangent (beyond CalculiX, which updates them only when pairing and holds them
            constant in the tangent).
        max_depth: Reject nodes deeper than this below the master face (beyond CalculiX, which has
            no limit).
        walk_from_previous_face: Start each node's face search at its current face instead of the
            nearest centroid (beyond CalculiX; default): a node stays on its face while that face
            holds it within the search tolerance, which stops the face ping-pong of nodes on
            shared edges during re-pairing. False reproduces CalculiX's search (the deck runner's
            default). Ties are decided in a frame of the model (docs/method.md §3.2).
        contact_start_slope: In the first Newton iteration of an attempt, give springs at the
            kink of the LINEAR law (``|d| <= eps``, e.g. bodies touching at the increment start)
            the slope ``K`` instead of ``K/2`` (beyond CalculiX; default; docs/method.md §7.1).
            Saves an iteration where contact starts at ``d = 0``; the converged state is the same.
            False is CalculiX's tangent (the deck runner's default).
        constraints: Linear multi-point constraints (CalculiX ``*EQUATION``), enforced by
            elimination (docs/method.md §13.1); in parallel each process gives those among its
            nodes (ghosts included), the union counts (docs/method.md §14.6).
        element_forces: Linear form in the test function of ``F`` whose element vectors are the
            element nodal forces averaged by the convergence test
            (:meth:`average_element_force`); default ``F`` itself (CalculiX uses the internal
            forces only).
        friction_tangent: ``"consistent"`` (exact derivative of the friction force) or ``"ccx"``
            (CalculiX's, projection point frozen in the slip increment), docs/method.md §11.2.
        projection_tangent: ``"exact"`` (a projection clamped to a face edge or corner is
            differentiated as such) or ``"ccx"`` (the interior formula everywhere, CalculiX's
            Newton path), docs/method.md §6.1.
        reset_friction_on_separation: A slave node that was not in contact at the last converged
            increment starts with a fresh friction state when it touches (default). False keeps
            CalculiX's stale state (docs/method.md §11.3).
        friction_in_tension: Apply ``mu |F_N|`` also when the linear law gives tension, as
            CalculiX does; by default there is no friction in tension.
        small_sliding_rule: ``"per_pair"`` (each pair's ``small_sliding`` flag) or
            ``"last_pair"`` (CalculiX: the last pair's flag decides for all), docs/method.md §11.6.
        overlap_ramp: ``"first_increment"`` (CalculiX: the initial overlap is scaled by the
            increment's time fraction in the first increment only) or ``"linear"`` (over the whole
            first step, as CalculiX's manual describes), docs/method.md §11.6.
        form_compiler_options, jit_options: Passed to dolfinx's form compiler and JIT.
        history: Material states the increments carry (:class:`MaterialHistory`, e.g.
            :class:`~dolfinx_ntf.J2Plasticity`): evaluated before every residual, committed when
            an increment converges, rolled back when an attempt fails.
        reuse_bulk_jacobian: When the bulk Jacobian form does not contain ``u`` (a linear material
            at small strain), assemble it once and copy it at later iterations while its inputs
            are unchanged (``BulkJacobian`` of ``fem/bulk_jacobian.py``; one more matrix in
            memory). False assembles it at every iteration.
    """

    def __init__(
        self,
        F: ufl.form.Form,
        u: dolfinx.fem.Function,
        pairs: typing.Sequence[ContactPair],
        bcs: typing.Sequence[compat.DirichletBC] = (),
        J: ufl.form.Form | None = None,
        *,
        symmetric: bool = False,
        linearize_area: bool = False,
        max_depth: float | None = None,
        walk_from_previous_face: bool = True,
        contact_start_slope: bool = True,
        element_forces: ufl.Form | None = None,
        constraints: typing.Sequence[LinearConstraint | LinearConstraintBlock] = (),
        friction_tangent: str = "consistent",
        reset_friction_on_separation: bool = True,
        friction_in_tension: bool = False,
        overlap_ramp: str = "first_increment",
        small_sliding_rule: str = "per_pair",
        form_compiler_options: dict | None = None,
        jit_options: dict | None = None,
        reuse_bulk_jacobian: bool = True,
        projection_tangent: str = "exact",
        history: typing.Sequence[MaterialHistory] = (),
    ) -> None:
        pairs, bcs = _check_arguments(F, u, pairs, bcs, J, max_depth, bool(history))
        options = compat.jit_keywords(form_compiler_options, jit_options)
        V = u.function_space
        self._L = dolfinx.fem.form(F, **options)
        self._a = dolfinx.fem.form(
            ufl.derivative(F, u, ufl.TrialFunction(V)) if J is None else J, **options
        )
        self.bcs = bcs
        if friction_tangent not in TANGENT_MODES:
            raise ValueError(
                f"ContactProblem: friction_tangent must be one of {TANGENT_MODES}, "
                f"got {friction_tangent!r}"
            )
        if projection_tangent not in ("exact", "ccx"):
            raise ValueError(
                "ContactProblem: projection_tangent must be 'exact' or 'ccx', "
                f"got {projection_tangent!r}"
            )
        self.projection_tangent = projection_tangent
        self.u = u
        self.symmetric = symmetric
        self.friction_tangent = friction_tangent
        self.friction_in_tension = bool(friction_in_tension)
        self.linearize_area = linearize_area
        ccx_rings = [p.name or f"pair {k}" for k, p in enumerate(pairs) if p.area_weights == "ccx"]
        if linearize_area and ccx_rings:
            raise ValueError(
                f"{ccx_rings[0]}: area_weights = 'ccx' holds its areas between pairings; "
                "linearize_area = True is not supported with it"
            )
        self.contact_start_slope = contact_start_slope
        self._element_forces, self._element_space = _broken(
            F if element_forces is None else element_forces, V, options
        )
        self._element_force_vector = compat.create_vector(self._element_forces)
        self.assembler = ContactAssembler(V, self.a, self.bcs)
        self.bulk_jacobian = BulkJacobian(
            ufl.derivative(F, u, ufl.TrialFunction(V)) if J is None else J,
            u,
            enabled=reuse_bulk_jacobian,
        )
        #: Face centres of C3D20's space: its quad9 faces are quad8 faces (docs/method.md §13.5).
        self._face_centres = serendipity.face_centres(constraints)
        self._quad_centres = serendipity_quad.has_quad_centres(constraints)  # CPE8 ... (§23)
        #: The pairs' states, the halo and the search, in one
        #: :class:`~dolfinx_ntf.contact.pairing.Pairing`.
        self.pairing = Pairing(
            u,
            pairs,
            face_centres=self._face_centres,
            linear_midsides=serendipity.linear_midsides(constraints),
            extend_numbering=lambda halo: self.assembler.extend(halo, u),
            max_depth=max_depth,
            walk_from_previous_face=walk_from_previous_face,
            reset_friction_on_separation=reset_friction_on_separation,
            overlap_ramp=overlap_ramp,
            small_sliding_rule=small_sliding_rule,
        )
        self.iteration = 0
        self.count_changed = False
        #: Re-pair at the start of the next Newton iteration even outside the schedule.
        self.repair_next_iteration = False
        self.pairings = 0
        #: Springs over all processes at the last pairing (:attr:`num_springs`: this process's).
        self.total_springs = 0
        #: Slave nodes over all processes that moved to another master face at the last pairing.
        self.total_face_changes = 0
        self._pattern_checked = False
        #: The vector the last :meth:`F` filled; a re-pairing in :meth:`J` re-assembles it (the
        #: right-hand side of the coming solve). A driver whose last residual went elsewhere (a
        #: SNES line search's work vector) points it at its own residual vector before :meth:`J`.
        self.residual_vector: PETSc.Vec | None = None
        #: Whether :meth:`assemble_jacobian` measures :attr:`bulk_norm` (a solver's round-off
        #: floor asks for it).
        self.measure_bulk_norm = False
        #: Largest row sum of the last bulk Jacobian, before the springs were added.
        self.bulk_norm = 0.0
        self._first_pairing_done = False
        self.matrix: PETSc.Mat | None = None
        #: Optional nodal forces (a Function on V, e.g. CalculiX ``*CLOAD``) subtracted from the
        #: residual.
        self.nodal_loads: dolfinx.fem.Function | None = None
        #: Called as ``callback(problem)`` after every pairing (e.g. to write contact-element
        #: files); the springs are used in Newton iteration ``max(problem.iteration, 1)`` of the
        #: increment.
        self.pairing_callbacks: list[typing.Callable[[ContactProblem], None]] = []
        #: Extra terms added to the residual and the Jacobian after the bulk form and the springs
        #: (e.g. the inertia of a dynamic step, docs/method.md §12).
        self.extra_terms: list[ResidualTerm] = []
        #: The nodal velocity of the running dynamic step (set by
        #: :class:`~dolfinx_ntf.DynamicStep`); the pairs' contact damping acts only while it is
        #: set (docs/method.md §29).
        self.node_velocity: NodeVelocity | None = None
        #: Elements between arbitrary nodes assembled with the springs (e.g. discrete springs,
        #: docs/method.md §18); add them before the first step.
        self.element_terms: list[ElementTerm] = []
        self._element_blocks: list[GlobalBlocks] = []
        #: Objects the outputs derive from this problem and keep with it for later calls, by name
        #: (e.g. the recovered pressure's compiled forms, ``outputs/results.py``).
        self.output_cache: dict[str, typing.Any] = {}
        #: Material states evaluated before every residual and committed with the friction state
        #: (:class:`MaterialHistory`, docs/method.md §21).
        self.history: list[MaterialHistory] = list(history)
        self._elastic_start = False  # begin_increment(elastic_start=True) sets it (§33)
        self._elastic_contact = "iterate"  # begin_increment(elastic_contact=...) sets it (§33.4)
        for term in self.history:
            missing = [
                name
                for name in ("evaluate", "increment_converged", "increment_rejected")
                if not callable(getattr(term, name, None))
            ]
            if missing:
                raise TypeError(
                    f"ContactProblem: history entries must be MaterialHistory objects (such as "
                    f"J2Plasticity); {validation.describe(term)} lacks {missing}"
                )
        self.constraints = list(constraints)
        self.elimination: ConstraintElimination | None = None
        #: The reduced Jacobian the linear solver uses when there are constraints.
        self.reduced_matrix: PETSc.Mat | None = None
        self._eliminate()

    def _eliminate(self) -> None:
        """(Re)build the elimination of the constraints for the current Dirichlet conditions."""
        if self.elimination is not None:
            self.elimination.destroy()
            self.elimination, self.reduced_matrix = None, None
        V = self.u.function_space
        comm = V.mesh.comm
        if not comm.allreduce(len(self.constraints), op=MPI.MAX):
            return

        def check() -> None:
            for c in self.constraints:
                validation.check_type(
                    c, (LinearConstraint, LinearConstraintBlock), "ContactProblem: constraints"
                )

        collectives.collectively(comm, check)
        prescribed = [bc.dof_indices()[0] for bc in self.bcs]
        prescribed = np.concatenate(prescribed) if prescribed else np.zeros(0, np.int64)
        if comm.size > 1:  # every process's constraints, in the global numbering (§14.6)
            self.elimination = collectives.collectively(
                comm, distributed_elimination, V, self.constraints, prescribed
            )
            return
        self.elimination = ConstraintElimination(
            self.u.x.array.size, self.constraints, prescribed, comm
        )

    @property
    def L(self) -> compat.Form:
        """The compiled residual form ``F``."""
        return self._L

    @property
    def a(self) -> compat.Form:
        """The compiled Jacobian form (``J``, or the derivative of ``F``)."""
        return self._a

    # -- state -------------------------------------------------------------------------------------

    def average_element_force(self) -> float:
        """CalculiX's average force, contact springs included. Collective.

        The mean absolute element nodal force over the elements, their nodes and the directions.
        """
        vector = self._element_force_vector
        with vector.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(vector, self._element_forces)
        values = vector.array_r  # owned entries: broken dofs belong to one cell each
        prisms = self._element_space.mesh.topology.cell_type == dolfinx.mesh.CellType.prism
        if self._face_centres.size and prisms:  # C3D15: its 15 nodes' (docs/method.md §34)
            values = serendipity_wedge.wedge_forces_on_nodes(values, self._element_space)
        elif self._face_centres.size:  # C3D20: the forces of its 20 nodes (§13.5)
            values = serendipity.element_forces_on_nodes(values, self._element_space)
        elif self._quad_centres:  # 8-node quadrilaterals: the forces of their 8 nodes
            values = serendipity_quad.quad_forces_on_nodes(values, self._element_space)
        total, count = float(np.abs(values).sum()), values.size
        for state in self.states:
            if state.evaluation is not None and state.num_springs:
                forces = state.evaluation.forces
                total += float(np.abs(forces).sum())
                count += forces.size
        for term in [*self.extra_terms, *self.element_terms]:  # (sum of |force|, count)
            extra_total, extra_count = term.force_sum()
            total, count = total + extra_total, count + extra_count
        comm = self.u.function_space.mesh.comm
        total, count = comm.allreduce(total), comm.allreduce(count)
        return total / max(count, 1)

    @property
    def states(self) -> list[PairState]:
        """The state of every pair at the current pairing (:attr:`pairing`'s)."""
        return self.pairing.states

    @property
    def halo(self) -> NodeHalo | None:
        """Contact nodes of other processes (docs/method.md §14); None in serial."""
        return self.pairing.halo

    @property
    def small_sliding(self) -> bool:
        """True when no pair is re-paired inside increments (all pairs small sliding)."""
        return self.pairing.small_sliding

    @property
    def has_friction(self) -> bool:
        """Whether any pair has friction now (the Jacobian is then unsymmetric)."""
        return self.pairing.has_friction

    @property
    def has_damping(self) -> bool:
        """Whether any pair has contact damping (an unsymmetric tangent in dynamic steps)."""
        return any(s.pair.interaction.damping is not None for s in self.states)

    @property
    def face_changes(self) -> int:
        """Slave nodes that kept a spring at the last pairing but moved to another master face."""
        return self.pairing.face_changes

    @property
    def num_springs(self) -> int:
        """Contact spring elements of this process over all pairs (``total_springs`` counts all)."""
        return self.pairing.num_springs

    @property
    def walk_from_previous_face(self) -> bool:
        """Whether each node's search starts at its current face (the stable search)."""
        return self.pairing.walk_from_previous_face

    @property
    def reference_coordinates(self) -> np.ndarray:
        """Reference coordinates of the nodes (local with ghosts, then the halo's), shape (N, 3)."""
        return self.pairing.reference

    def current_coordinates(self) -> np.ndarray:
        """Node coordinates X + u (local nodes with ghosts, then the halo's). Collective."""
        return self.pairing.current_coordinates()

    def unpaired_contacts(self) -> int:
        """Slave nodes that a pairing now would give a spring but that have none. Collective.

        For example nodes that penetrated after the pairing froze at iteration 8.
        """
        return self.pairing.unpaired_contacts()

    # -- pairing -----------------------------------------------------------------------------------

    def begin_increment(
        self,
        time_fraction: float,
        *,
        static: bool = True,
        elastic_start: bool = False,
        elastic_contact: str = "iterate",
    ) -> None:
        """Increment-start pairing at the last converged displacement (docs/method.md §3.1, §3.5).

        Args:
            time_fraction: Relative step time at the end of the increment (tau of the overlap ramp).
            static: Static step (the initial overlap is ramped) or not.
            elastic_start: CalculiX's elastic first iteration (docs/method.md §33): the first
                iterate evaluates :attr:`history` elastically if the prescribed displacements
                change by more than 1e-5 there.
            elastic_contact: The springs in that same first iterate (docs/method.md §33.4):
                ``"iterate"`` at the iterate, as in the others; ``"start"`` at the increment
                start (CalculiX 2.20's static steps: the prescribed values are not yet in the
                springs' force and tangent); ``"stick"`` at the iterate with every friction
                spring's force stuck (the forced stick of CalculiX's elastic evaluation).
                Independent of ``elastic_start``.
        """
        if elastic_contact not in ELASTIC_CONTACT:
            raise ValueError(
                f"ContactProblem: elastic_contact must be one of {ELASTIC_CONTACT}, "
                f"got {elastic_contact!r}"
            )
        if elastic_start:
            for term in self.history:
                if not callable(getattr(term, "evaluate_elastic", None)):
                    raise TypeError(
                        f"ContactProblem: elastic_start needs history entries with "
                        f"evaluate_elastic(); {validation.describe(term)} has none"
                    )
        self._elastic_start = elastic_start
        self._elastic_contact = elastic_contact
        self.pairing.begin_increment(time_fraction, static=static)
        first = not self._first_pairing_done
        self.iteration = 0
        self.count_changed = False
        self.repair_next_iteration = False
        self.pair(record_overlap=first)
        self._first_pairing_done = True
        self.ensure_matrix()

    def begin_step(self) -> None:
        """Tell the problem that a new step starts (ends the linear overlap ramp of step 1)."""
        self.pairing.begin_step()

    def end_increment(self) -> None:
        """Accept the converged increment: commit the friction state and the material history.

        docs/method.md §11.3 (friction) and §21 (:attr:`history`).
        """
        if self.has_friction:
            self.evaluate(tangent=False)
        self.pairing.end_increment()
        for term in self.history:
            term.increment_converged()

    def reject_increment(self) -> None:
        """A failed attempt: ``u`` is back at the increment start; roll the history back (§21).

        The friction state needs nothing: it is committed by :meth:`end_increment` only.
        """
        for term in self.history:
            term.increment_rejected()

    def pair(self, *, record_overlap: bool = False, large_sliding_only: bool = False) -> int:
        """Pair every slave node with a master face at the current displacement.

        Args:
            record_overlap: Record the initial overlap (first pairing of the analysis).
            large_sliding_only: Re-pair only the pairs without small sliding.

        Returns:
            The number of springs (over all processes).
        """
        adjusted = self.pairing.adjusted
        count, changes = self.pairing.pair(
            record_overlap=record_overlap, large_sliding_only=large_sliding_only
        )
        if self.pairing.adjusted > adjusted:  # ADJUST moved nodes: the centres follow (§38.6)
            follow_geometric_rows(self.u.function_space, self.pairing.reference, self.constraints)
        self.pairings += 1
        self._pattern_checked = False
        self.total_springs = count
        self.total_face_changes = changes
        if self.iteration >= 1 and changes:
            details_logger.info(
                " Number of contact spring elements=%d (%d changed face)", count, changes
            )
        else:
            details_logger.info(" Number of contact spring elements=%d", count)
        for callback in self.pairing_callbacks:
            callback(self)
        return count

    # -- springs -----------------------------------------------------------------------------------

    def evaluate(self, *, tangent: bool = True, force_stick: bool = False) -> list[SpringBlocks]:
        """Evaluate every spring at the current displacement; returns the blocks to assemble.

        With ``tangent`` False only the forces are computed (no stiffness blocks); with
        ``force_stick`` every friction spring sticks (the elastic first iterate, §33.4).
        """
        coords = self.current_coordinates()
        blocks = []
        symmetric = self.symmetric and not self.has_friction
        velocities, rate = self._velocities(coords)
        for state in self.states:
            law = state.pair.interaction.law
            blocks += evaluate_pair(
                state,
                coords,
                start_law(law) if self.contact_start_slope and self.iteration == 0 else law,
                reference=self.pairing.reference,
                gap_shift=self.pairing.gap_shift(state, state.spring_slave),
                tangent=tangent,
                symmetric=symmetric,
                linearize_area=self.linearize_area,
                friction_in_tension=self.friction_in_tension,
                friction_tangent=self.friction_tangent,
                projection_tangent=self.projection_tangent,
                velocities=velocities,
                velocity_rate=rate,
                force_stick=force_stick,
            )  # the start slope: contact_start_slope, docs/method.md §7.1
        return blocks

    def _velocities(self, coords: np.ndarray) -> tuple[np.ndarray | None, float]:
        """Node velocities (like ``coords``) and ``dv/du`` when a damped pair needs them."""
        if self.node_velocity is None or not self.has_damping:
            return None, 0.0
        velocity = self.node_velocity
        offset = self.pairing.nodal_vectors(velocity.offset)
        return offset + velocity.rate * (coords - self.pairing.reference), float(velocity.rate)

    def ensure_matrix(self) -> PETSc.Mat:
        """The Jacobian matrix, recreated when the current springs need couplings it lacks."""
        blocks = [SpringBlocks(s.element_nodes, s.element_nodes) for s in self.states]
        if self.linearize_area:
            coords = self.current_coordinates()
            blocks += [area_block(s, coords, values=False) for s in self.states]
        couplings = [term.node_couplings() for term in self.element_terms]
        couplings = np.concatenate(couplings) if couplings else None
        if self.matrix is None or not self.assembler.has_pattern(blocks, couplings):
            if self.matrix is not None:
                self.matrix.destroy()
            comm = self.u.function_space.mesh.comm  # a failed patch lookup fails on all (§14.4)
            reserved = collectives.collectively(comm, self.pairing.reserved_blocks)
            self.matrix = self.assembler.create_matrix(blocks + reserved, couplings)
        self._pattern_checked = True
        return self.matrix

    # -- dolfinx callbacks -------------------------------------------------------------------------
    #
    # CalculiX's order (docs/method.md §3.1, §7.1): Newton iteration k >= 2 starts with a re-pairing
    # (k <= 8), assembles and solves with it, and the convergence check after the update uses that
    # same pairing. dolfinx calls form -> F -> (convergence check) -> J -> solve, so the re-pairing
    # happens in J, which then re-assembles the residual vector last given to F (the right-hand side
    # of the coming solve).

    def form(self, x: PETSc.Vec) -> None:
        """Before F: update the ghost values of ``x`` and evaluate the current pairing's springs."""
        first = self._elastic_start or self._elastic_contact != "iterate"
        elastic = first and self._prescribed_change(x) > _ELASTIC_START_CHANGE
        contact = self._elastic_contact if elastic else "iterate"
        elastic = elastic and self._elastic_start
        self._elastic_start, self._elastic_contact = False, "iterate"
        blocks = None
        if contact == "start":  # the springs before the prescribed values enter x (§33.4)
            x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            blocks = self.evaluate(tangent=True)
        if self.elimination is not None:  # before the ghost update: ghosts get the new values
            # Prescribed values first: the reduced Jacobian cannot carry their lifting through
            # the constraints (C3D20's centres move with the prescribed nodes, §13.1, §13.5).
            dolfinx.fem.petsc.set_bc(x, self.bcs)
            self.elimination.back_substitute(x)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        for term in self.history:  # stresses at the iterate, from the committed state (§21)
            if elastic:  # ccx's elastic first iteration (§33)
                term.evaluate_elastic()
            else:
                term.evaluate()
        if blocks is None:
            blocks = self.evaluate(tangent=True, force_stick=contact == "stick")
        self._blocks = blocks
        self._element_blocks = [term.evaluate(x, self.bcs) for term in self.element_terms]

    def _prescribed_change(self, x: PETSc.Vec) -> float:
        """Largest change of a prescribed value from ``x`` to the conditions' values (collective).

        Before the first update of an increment: how far the conditions move the prescribed
        dofs from the increment start (0 once eliminated values were set into ``x``, so it is
        taken before :meth:`form` sets them).
        """
        target = x.copy()
        dolfinx.fem.petsc.set_bc(target, self.bcs)
        target.axpy(-1.0, x)
        change = target.norm(PETSc.NormType.NORM_INFINITY)
        target.destroy()
        return float(change)

    def F(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Assemble the bulk residual plus the spring forces at ``x`` into ``b``."""
        self.residual_vector = b
        self.assemble_residual(x, b)

    def assemble_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """The residual at ``x`` with the springs last evaluated by :meth:`form` into ``b``."""
        with b.localForm() as b_local:
            b_local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.L)
        dolfinx.fem.petsc.apply_lifting(b, [self.a], [self.bcs], [x], -1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.assembler.add_to_vector(b, self._blocks)
        if self._element_blocks:
            self.assembler.add_global_to_vector(b, self._element_blocks)
        if self.nodal_loads is not None:
            b.axpy(-1.0, compat.petsc_vector(self.nodal_loads))
        for term in self.extra_terms:
            term.add_to_residual(x, b)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)
        if self.elimination is not None:
            self.elimination.reduce_vector(
                b, lambda r: dolfinx.fem.petsc.set_bc(r, self.bcs, x, -1.0)
            )

    def spring_force_sizes(self, out: PETSc.Vec) -> None:
        """The sum of the absolute spring forces at every dof, into ``out``. Collective.

        The springs last evaluated by :meth:`form`, Dirichlet rows included; ``out`` has the
        layout of the residual vector (each owner gets its rows, from every process's springs).
        """
        with out.localForm() as local:
            local.set(0.0)
        blocks = [
            dataclasses.replace(block, vector=np.abs(block.vector))
            for block in self._blocks
            if block.vector is not None
        ]
        self.assembler.add_to_vector(out, blocks, dirichlet_rows=True)

    def J(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Start Newton iteration ``iteration``: re-pair on schedule, assemble the Jacobian.

        The Jacobian at the iterate ``x`` goes into ``A``. A re-pairing re-assembles the residual
        vector too (:meth:`start_iteration`, then :meth:`assemble_jacobian`).
        """
        self.start_iteration(x)
        self.assemble_jacobian(x, A)

    def start_iteration(self, x: PETSc.Vec) -> None:
        """Count a new Newton iteration at ``x``; re-pair on schedule or when asked.

        A re-pairing evaluates the springs again and re-assembles :attr:`residual_vector`.
        """
        self.iteration += 1
        self.count_changed = False
        scheduled = not self.small_sliding and 2 <= self.iteration <= LAST_REPAIRING_ITERATION
        if scheduled or self.repair_next_iteration:
            before = self.u.function_space.mesh.comm.allreduce(self.num_springs)
            self.count_changed = (
                self.pair(large_sliding_only=not self.repair_next_iteration) != before
            )
            self.repair_next_iteration = False
            self.form(x)
            if self.residual_vector is not None:
                self.F(x, self.residual_vector)

    def assemble_jacobian(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The Jacobian at ``x`` with the springs last evaluated, into ``A``."""
        pattern = (self.assembler.pattern_merges, self.assembler.matrix_rebuilds)
        self.bulk_jacobian.assemble(A, self.a, self.bcs, pattern)
        if self.measure_bulk_norm:
            self.bulk_norm = A.norm(PETSc.NormType.NORM_INFINITY)
        self.assembler.add_to_matrix(A, self._blocks, check_pattern=not self._pattern_checked)
        self._pattern_checked = True
        self.assembler.add_global_to_matrix(A, self._element_blocks)
        A.assemble()
        for term in self.extra_terms:
            term.add_to_jacobian(x, A)
        if self.elimination is not None:
            key = (A.handle, self.assembler.pattern_merges, self.assembler.matrix_rebuilds)
            self.reduced_matrix = self.elimination.reduce_matrix(A, key)

    def destroy(self) -> None:
        """Destroy the PETSc matrix the problem owns (the Jacobian). Collective.

        The solver's vectors belong to :class:`~dolfinx_ntf.ContactNewtonSolver` (its own
        ``destroy``). Using the problem afterwards creates a new matrix.
        """
        if self.matrix is not None:
            self.matrix.destroy()
            self.matrix = None
        self.bulk_jacobian.release()
        if self.elimination is not None:
            self.elimination.release()
            self.reduced_matrix = None
        self.pairing.destroy()

    def __enter__(self) -> ContactProblem:
        return self

    def __exit__(self, *args: object) -> None:
        self.destroy()

    def set_bcs(self, bcs: typing.Sequence[compat.DirichletBC]) -> None:
        """Replace the Dirichlet conditions by ``bcs`` (e.g. between steps).

        Contact entries skip the new constrained dofs.
        """
        self.bcs = list(bcs)
        self.assembler.set_bcs(self.bcs)
        self._eliminate()


def _broken(
    form: ufl.Form, V: dolfinx.fem.FunctionSpace, options: dict
) -> tuple[compat.Form, dolfinx.fem.FunctionSpace]:
    """``form`` with its test function replaced by one of the discontinuous space of its degree.

    The assembled vector then holds every element's nodal forces separately. Returns the form
    and that space.
    """
    arguments = form.arguments()
    if len(arguments) != 1:
        raise ValueError(
            f"element_forces: a linear form in the test function is needed, got a form with "
            f"{len(arguments)} arguments"
        )
    mesh = V.mesh
    family = "DQ" if mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron else "DG"
    W = compat.vector_space(mesh, family, compat.space_degree(V))
    return dolfinx.fem.form(ufl.replace(form, {arguments[0]: ufl.TestFunction(W)}), **options), W


def _check_arguments(
    F: object,
    u: object,
    pairs: object,
    bcs: object,
    J: object,
    max_depth: object,
    history: bool = False,
) -> tuple[list[ContactPair], list[compat.DirichletBC]]:
    """The arguments of :class:`ContactProblem`; returns ``(pairs, bcs)`` as lists."""
    owner = "ContactProblem"
    validation.check_displacement(u, owner)
    collectives.collectively(u.function_space.mesh.comm, _check_geometry, u.function_space.mesh)
    validation.check_residual(F, u, owner, J, through=history)
    pairs = validation.check_sequence(
        pairs, ContactPair, f"{owner}: pairs", single_hint="pass [pair] instead of pair"
    )
    validation.check_positive(max_depth, f"{owner}: max_depth", allow_none=True)
    return pairs, validation.check_bcs(bcs, owner)


def _check_geometry(mesh: dolfinx.mesh.Mesh) -> None:
    """Raise ``ValueError`` naming the first node whose coordinates are not finite."""
    x = mesh.geometry.x
    bad = np.flatnonzero(~np.isfinite(x).all(axis=1))
    if bad.size:
        raise ValueError(
            f"ContactProblem: the mesh has {bad.size} node(s) with non-finite coordinates (first: "
            f"geometry node {bad[0]} of process {mesh.comm.rank}, {x[bad[0]].tolist()}): check "
            "the mesh file or the gmsh model"
        )
