"""Contact pairs and the nonlinear problem that adds their springs to dolfinx's residual.

:class:`ContactProblem` is a :data:`~dolfinx_ntf.compat.NewtonSolverNonlinearProblem` whose
callbacks, besides assembling the user's UFL forms, (re-)pair slave nodes with master faces on
CalculiX's schedule (docs/method.md §3.1) and add the spring elements (docs/method.md §5, §6). The
step driver in ``solver.py`` tells it when an increment starts.
"""

from __future__ import annotations

import logging
import typing
from dataclasses import dataclass, field

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.adjust import adjusted_nodes, move_reference_nodes
from dolfinx_ntf.contact.assembly import ContactAssembler, SpringBlocks
from dolfinx_ntf.fem import serendipity
from dolfinx_ntf.fem.bulk_jacobian import BulkJacobian
from dolfinx_ntf.fem.constraints import (
    ConstraintElimination,
    LinearConstraint,
    LinearConstraintBlock,
)
from dolfinx_ntf.fem.surfaces import (
    FacetSurface,
    NodeSurface,
    SlaveSurface,
    SurfaceFaces,
    reference_coordinates,
    resolve_master,
    resolve_slave,
)
from dolfinx_ntf.kernels.friction import TANGENT_MODES, FrictionInput
from dolfinx_ntf.kernels.friction_state import FrictionState
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw, SurfaceInteraction
from dolfinx_ntf.kernels.rigid import RigidSurface, rigid_master, spring_evaluator
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.spring_areas import spring_area_gradients, spring_areas
from dolfinx_ntf.kernels.springs import SpringEvaluation
from dolfinx_ntf.kernels.start_slope import start_law
from dolfinx_ntf.kernels.tie_frame import TieFrame, frame_from_moments, point_moments
from dolfinx_ntf.parallel import collectives, master_exchange, surface_distribution
from dolfinx_ntf.parallel.global_constraints import distributed_elimination
from dolfinx_ntf.parallel.halo import NodeHalo

__all__ = ["ContactPair", "ContactProblem", "PairState"]

logger = logging.getLogger("dolfinx_ntf")

#: Re-pairing happens at the start of iterations 2..LAST_REPAIRING_ITERATION
#: (docs/method.md §3.1, ccx: iit <= 8).
LAST_REPAIRING_ITERATION = 8
#: Relative walk tolerance of the triangle search (docs/method.md §3.2).
SEARCH_TOLERANCE = 1e-3


@dataclass
class ContactPair:
    """One node-to-face contact pair (CalculiX ``*CONTACT PAIR, TYPE=NODE TO SURFACE``).

    Args:
        slave: Face-based (:class:`FacetSurface`) or node-based (:class:`NodeSurface`) slave
            surface.
        master: Face-based master surface, or a rigid analytical surface (one-node springs,
            docs/method.md §15.1).
        interaction: Pressure-overclosure law and optional friction; may be replaced between
            steps (new mu and lambda act from then on, the friction state is kept).
        small_sliding: Pair only at increment starts. Per pair by default; with
            ``ContactProblem(small_sliding_rule="last_pair")`` the flag of the *last* pair decides
            for all, as in CalculiX.
        name: Label used in messages and output.
        active: Inactive pairs generate no springs (``*MODEL CHANGE``); a pair that becomes
            active again starts with a fresh friction state.
        adjust: CalculiX's ADJUST at the first pairing of the analysis (docs/method.md §11.5): a
            distance ``a >= 0`` (slave nodes with clearance ``g <= a`` are moved onto the
            master) or a :class:`NodeSurface` of the nodes to move; None moves nothing.
    """

    slave: FacetSurface | NodeSurface
    master: FacetSurface | RigidSurface
    interaction: SurfaceInteraction
    small_sliding: bool = False
    name: str = ""
    active: bool = True
    adjust: float | NodeSurface | None = None

    def __post_init__(self) -> None:
        """Check the kinds of the arguments (``TypeError``/``ValueError`` naming them)."""
        owner = (
            f"ContactPair {self.name!r}"
            if isinstance(self.name, str) and self.name
            else ("ContactPair")
        )
        validation.check_type(self.slave, (FacetSurface, NodeSurface), f"{owner}: slave")
        if isinstance(self.master, NodeSurface):
            raise ValueError(
                f"{owner}: the master surface must be a FacetSurface (face-based), got a "
                "NodeSurface; only the slave surface may be node-based"
            )
        validation.check_type(self.master, (FacetSurface, RigidSurface), f"{owner}: master")
        validation.check_type(
            self.interaction,
            SurfaceInteraction,
            f"{owner}: interaction",
            "wrap the law: SurfaceInteraction(law)"
            if isinstance(self.interaction, PressureOverclosureLaw)
            else "",
        )
        validation.check_type(self.name, str, f"{owner}: name")
        if self.adjust is not None and not isinstance(self.adjust, NodeSurface):
            if isinstance(self.adjust, bool) or not isinstance(self.adjust, (int, float)):
                raise TypeError(
                    f"{owner}: adjust must be a distance >= 0, a NodeSurface or None, got "
                    f"{validation.describe(self.adjust)}"
                )
            if not (np.isfinite(self.adjust) and self.adjust >= 0):
                raise ValueError(
                    f"{owner}: adjust must be a finite distance >= 0, got {self.adjust}"
                )


@dataclass
class PairState:
    """Numbering-level data of a pair and its springs at the current pairing."""

    pair: ContactPair
    slave: SlaveSurface
    master_faces: SurfaceFaces
    master: MasterSurface
    overlap: np.ndarray  # (S,) initial overlap g0 per slave node (docs/method.md §3.5)
    spring_slave: np.ndarray = field(
        default_factory=lambda: np.empty(0, dtype=np.int64)
    )  # index into slave.nodes
    spring_face: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    spring_area: np.ndarray = field(default_factory=lambda: np.empty(0))
    xi: np.ndarray | None = None
    evaluation: SpringEvaluation | None = None
    found_face: np.ndarray | None = None  # face of every slave node at the last pairing, -1: none
    face_changes: int = 0  # slave nodes paired before and after the last pairing, on another face
    friction: FrictionState | None = None  # friction history per slave node (docs/method.md §11.3)
    adjust_nodes: np.ndarray | None = None  # ADJUST node set as slave dofs
    was_active: bool = True  # the pair was active at the previous pairing

    @property
    def num_springs(self) -> int:
        """Number of contact spring elements of this pair."""
        return int(self.spring_slave.size)

    @property
    def element_nodes(self) -> np.ndarray:
        """(N, n+1) spring nodes: master face nodes, then the slave node."""
        faces = self.master_faces.faces[self.spring_face]
        return np.hstack([faces, self.slave.nodes[self.spring_slave][:, None]])


class ContactProblem(compat.NewtonSolverNonlinearProblem):
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
        reuse_bulk_jacobian: When the bulk Jacobian form does not contain ``u`` (a linear material
            at small strain), assemble it once and copy it at later iterations while its inputs
            are unchanged (:class:`~dolfinx_ntf.fem.bulk_jacobian.BulkJacobian`; one more matrix in
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
    ) -> None:
        pairs, bcs = validation.check_problem(F, u, pairs, bcs, J, ContactPair, max_depth)
        super().__init__(
            F,
            u,
            bcs,
            J,
            **compat.jit_keywords(form_compiler_options, jit_options),
        )
        if friction_tangent not in TANGENT_MODES:
            raise ValueError(
                f"ContactProblem: friction_tangent must be one of {TANGENT_MODES}, "
                f"got {friction_tangent!r}"
            )
        if small_sliding_rule not in ("per_pair", "last_pair"):
            raise ValueError(
                "ContactProblem: small_sliding_rule must be 'per_pair' or 'last_pair', "
                f"got {small_sliding_rule!r}"
            )
        if overlap_ramp not in ("first_increment", "linear"):
            raise ValueError(
                "ContactProblem: overlap_ramp must be 'first_increment' or 'linear', "
                f"got {overlap_ramp!r}"
            )
        V = u.function_space
        self.u = u
        self.symmetric = symmetric
        self.friction_tangent = friction_tangent
        self.reset_friction_on_separation = bool(reset_friction_on_separation)
        self.friction_in_tension = bool(friction_in_tension)
        self.overlap_ramp = overlap_ramp
        self.small_sliding_rule = small_sliding_rule
        #: Steps begun so far (:meth:`begin_step`); the linear overlap ramp lasts step 1.
        self.step_count = 0
        self.linearize_area = linearize_area
        self.max_depth = max_depth
        self.walk_from_previous_face = walk_from_previous_face
        self.contact_start_slope = contact_start_slope
        self._reference = reference_coordinates(V)
        self._element_forces, self._element_space = _broken(
            F if element_forces is None else element_forces,
            V,
            compat.jit_keywords(form_compiler_options, jit_options),
        )
        self._element_force_vector = compat.create_vector(self._element_forces)
        self.assembler = ContactAssembler(V, self.a, self.bcs)
        self.bulk_jacobian = BulkJacobian(
            ufl.derivative(F, u, ufl.TrialFunction(V)) if J is None else J,
            u,
            enabled=reuse_bulk_jacobian,
        )
        #: Contact nodes of other processes (docs/method.md §14); None in serial.
        self.halo = NodeHalo(V) if V.mesh.comm.size > 1 else None
        #: Face centres of C3D20's space: its quad9 faces are quad8 faces (docs/method.md §13.5).
        self._face_centres = serendipity.face_centres(constraints)
        self._serendipity = bool(V.mesh.comm.allreduce(self._face_centres.size, op=MPI.MAX))
        self.states = [self._resolve(i, pair) for i, pair in enumerate(pairs)]
        if self.halo is not None:
            self._reference = self.halo.reference
            self.assembler.extend(self.halo, u)
        validation.check_distinct_pairs(V.mesh.comm, self._surfaces(), self._reference)
        self.time_fraction = 1.0  # relative step time tau at the end of the current increment
        self.static = True
        self.iteration = 0
        self.count_changed = False
        #: Re-pair at the start of the next Newton iteration even outside the schedule.
        self.repair_next_iteration = False
        self.pairings = 0
        #: Springs over all processes at the last pairing (:attr:`num_springs`: this process's).
        self.total_springs = 0
        self._pattern_checked = False
        self._residual_vector: PETSc.Vec | None = None
        self._first_pairing_done = False
        self._increment_start_u = self._displacement().copy()
        self.matrix: PETSc.Mat | None = None
        #: Optional nodal forces (a Function on V, e.g. CalculiX *CLOAD) subtracted from the
        #: residual.
        self.nodal_loads: dolfinx.fem.Function | None = None
        #: Called as ``callback(problem)`` after every pairing (e.g. to write contact-element
        #: files); the springs are used in Newton iteration ``max(problem.iteration, 1)`` of the
        #: increment.
        self.pairing_callbacks: list[typing.Callable[[ContactProblem], None]] = []
        #: Extra terms added to the residual and the Jacobian after the bulk form and the springs
        #: (e.g. the inertia of a dynamic step, docs/method.md §12): objects with
        #: ``add_to_residual(x, b)``, ``add_to_jacobian(x, A)`` and ``force_sum()`` (the sum of
        #: the absolute values of their nodal forces and how many there are, owned entries, for
        #: :meth:`average_element_force`).
        self.extra_terms: list[typing.Any] = []
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

    def _resolve(self, index: int, pair: ContactPair) -> PairState:
        name = pair.name or f"pair {index + 1}"
        V = self.u.function_space
        comm = V.mesh.comm
        slave = collectives.collectively(comm, resolve_slave, V, pair.slave, what=f"{name} slave")
        if self._serendipity:  # C3D20: quad8 slave faces, no face-centre slave nodes
            faces = serendipity.as_quad8(slave.faces, self._face_centres)
            keep = ~np.isin(slave.nodes, self._face_centres)
            faceless = None if slave.faceless is None else slave.faceless[keep]
            slave = SlaveSurface(slave.nodes[keep], faces, faceless)
        if isinstance(pair.master, RigidSurface):  # docs/method.md §15.1
            if pair.interaction.friction is not None or pair.adjust is not None:
                raise NotImplementedError(
                    f"{name}: friction and ADJUST against a rigid analytical master are not "
                    "supported yet; use a meshed master"
                )
            if self.halo is not None:  # the owned slave nodes; no master nodes (§14.6)
                slave = collectives.collectively(
                    comm,
                    surface_distribution.distribute_slave,
                    V,
                    self.halo,
                    pair.slave,
                    slave,
                    name,
                )
            faces, master = rigid_master(pair.master, lambda: self.time_fraction, f"{name} master")
            friction = FrictionState(slave.nodes.size)  # stays empty: the bookkeeping is shared
            return PairState(
                pair, slave, faces, master, np.zeros(slave.nodes.size), friction=friction,
                was_active=pair.active,
            )  # fmt: skip
        master_faces = collectives.collectively(
            comm, resolve_master, V, pair.master, what=f"{name} master"
        )
        if self._serendipity:
            master_faces = serendipity.as_quad8(master_faces, self._face_centres)
        patch = None
        if self.halo is not None and master_exchange.uses_exchange(comm, master_faces):  # §14.8
            slave, patch = collectives.collectively(
                comm, master_exchange.distribute_pair, self.halo, self.u, pair.slave, slave,
                master_faces, name,
            )  # fmt: skip
            master_faces = patch.faces
        elif self.halo is not None:
            slave, master_faces = collectives.collectively(
                comm,
                surface_distribution.distribute_pair,
                V,
                self.halo,
                pair.slave,
                slave,
                master_faces,
                name,
            )
        if patch is None and master_faces.faces.shape[0] == 0:
            raise ValueError(f"{name}: the master surface has no faces")
        master = patch or MasterSurface(
            master_faces.face_type,
            master_faces.faces,
            name=f"{name} master",
            coords=self._reference if self.halo is None else self.halo.reference,
        )
        both = np.intersect1d(slave.nodes, master_faces.nodes)
        error = None
        if both.size:
            x = (self._reference if self.halo is None else self.halo.reference)[both[0]]
            error = ValueError(
                f"{name}: {both.size} node(s) belong to both the slave and the master surface "
                f"(first at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}))"
            )
        validation.raise_collectively(comm, error)
        friction = FrictionState(
            slave.nodes.size, reset_on_separation=self.reset_friction_on_separation
        )
        adjust_nodes = None
        if isinstance(pair.adjust, NodeSurface):
            adjust_nodes = collectives.collectively(
                comm, resolve_slave, V, pair.adjust, what=f"{name} adjust"
            ).nodes
            if self.halo is not None:  # the union over processes, as extended nodes
                held = self.halo.local_global[adjust_nodes]
                adjust_nodes = self.halo.find(np.unique(np.concatenate(comm.allgather(held))))
                adjust_nodes = adjust_nodes[adjust_nodes >= 0]
        return PairState(
            pair,
            slave,
            master_faces,
            master,
            np.zeros(slave.nodes.size),
            friction=friction,
            was_active=pair.active,
            adjust_nodes=adjust_nodes,
        )

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
        if self._face_centres.size:  # C3D20: the forces of its 20 nodes (docs/method.md §13.5)
            values = serendipity.element_forces_on_nodes(values, self._element_space)
        total, count = float(np.abs(values).sum()), values.size
        for state in self.states:
            if state.evaluation is not None and state.num_springs:
                forces = state.evaluation.forces
                total += float(np.abs(forces).sum())
                count += forces.size
        for term in self.extra_terms:  # e.g. inertia forces: (sum of |force|, count)
            extra_total, extra_count = term.force_sum()
            total, count = total + extra_total, count + extra_count
        comm = self.u.function_space.mesh.comm
        total, count = comm.allreduce(total), comm.allreduce(count)
        return total / max(count, 1)

    @property
    def small_sliding(self) -> bool:
        """True when no pair is re-paired inside increments (all pairs small sliding)."""
        return all(self._small_sliding(s) for s in self.states)

    def _small_sliding(self, state: PairState) -> bool:
        """Whether the pair of ``state`` is paired at increment starts only."""
        if self.small_sliding_rule == "last_pair":
            return bool(self.states[-1].pair.small_sliding)
        return bool(state.pair.small_sliding)

    @property
    def has_friction(self) -> bool:
        """Whether any pair has friction now (the Jacobian is then unsymmetric)."""
        return any(s.pair.interaction.friction is not None for s in self.states)

    @property
    def face_changes(self) -> int:
        """Slave nodes that kept a spring at the last pairing but moved to another master face."""
        return sum(s.face_changes for s in self.states)

    @property
    def num_springs(self) -> int:
        """Contact spring elements of this process over all pairs (all processes: total_springs)."""
        return sum(s.num_springs for s in self.states)

    @property
    def reference_coordinates(self) -> np.ndarray:
        """Reference coordinates of the nodes (local with ghosts, then the halo's), shape (N, 3)."""
        return self._reference

    def _surfaces(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """(name, slave nodes, master facets) of every pair, for checks and messages."""
        return [
            (
                s.pair.name or f"pair {i + 1}",
                s.slave.nodes,
                s.master_faces.facets[s.master_faces.facets >= 0],  # -1: another process's
            )
            for i, s in enumerate(self.states)
        ]

    def _check_finite(self) -> None:
        """A non-finite displacement at a contact node: a ValueError naming node and position."""
        surfaces = []
        num_local = self.u.x.array.size // 3  # halo nodes are checked by their owners
        for (name, slave, _), state in zip(self._surfaces(), self.states):
            master = state.master_faces.nodes
            surfaces += [(f"{name} slave", slave), (f"{name} master", master[master < num_local])]
        comm = self.u.function_space.mesh.comm
        validation.check_finite_contact_nodes(comm, self.u, self._reference, surfaces)

    def current_coordinates(self) -> np.ndarray:
        """Node coordinates X + u (local nodes with ghosts, then the halo's). Collective."""
        return self._reference + self._displacement()

    def halo_grew(self) -> None:
        """Nodes were appended to the halo (a master patch grew, docs/method.md §14.8). Collective.

        The scatter, the contact numbering and the increment-start displacement follow.
        """
        known = self._increment_start_u.shape[0]
        self.halo.destroy()  # rebuilt on next use, with the new nodes
        self._reference = self.halo.reference
        self.assembler.extend(self.halo, self.u)
        start = compat.petsc_vector(self.u).duplicate()
        start.array[:] = self._increment_start_u[: self.halo.num_owned].ravel()
        extra = self.halo.values(start)[known - self.halo.num_local :]
        start.destroy()
        self._increment_start_u = np.vstack([self._increment_start_u, extra])

    def _displacement(self) -> np.ndarray:
        """u at the local nodes with ghosts, then at the halo's, shape (N, 3). Collective."""
        if self.halo is not None:
            return self.halo.displacement(self.u)
        return self.u.x.array.reshape(-1, 3)

    # -- pairing -----------------------------------------------------------------------------------

    def begin_increment(self, time_fraction: float, *, static: bool = True) -> None:
        """Increment-start pairing at the last converged displacement (docs/method.md §3.1, §3.5).

        Args:
            time_fraction: Relative step time at the end of the increment (tau of the overlap ramp).
            static: Static step (the initial overlap is ramped) or not.
        """
        self._check_finite()
        self.time_fraction = float(time_fraction)
        self.static = static
        self._increment_start_u = self._displacement().copy()  # halo nodes too: anchors
        first = not self._first_pairing_done
        keep = self.overlap_ramp == "linear" and self.step_count <= 1 and static
        for state in self.states:
            if not keep:
                state.overlap[:] = 0.0
            state.friction.begin_increment()
        self.iteration = 0
        self.count_changed = False
        self.repair_next_iteration = False
        self.pair(record_overlap=first)
        self._first_pairing_done = True
        self.ensure_matrix()

    def begin_step(self) -> None:
        """Tell the problem that a new step starts (ends the linear overlap ramp of step 1)."""
        self.step_count += 1
        if self.step_count > 1:
            for state in self.states:
                state.overlap[:] = 0.0

    def end_increment(self) -> None:
        """Accept the converged increment: commit the friction state (docs/method.md §11.3)."""
        if self.has_friction:
            self.evaluate(tangent=False)
        for state in self.states:
            state.friction.commit(state.spring_slave)

    def pair(self, *, record_overlap: bool = False, large_sliding_only: bool = False) -> int:
        """Pair every slave node with a master face at the current displacement.

        Args:
            record_overlap: Record the initial overlap (first pairing of the analysis).
            large_sliding_only: Re-pair only the pairs without small sliding.

        Returns:
            The number of springs (over all processes).
        """
        coords = self.current_coordinates()
        comm = self.u.function_space.mesh.comm
        with collectives.collective_errors(
            comm
        ):  # an error on one process is raised on all (§14.4)
            for state in self.states:
                if large_sliding_only and self._small_sliding(state):
                    continue
                self._pair_one(state, coords, record_overlap)
                if record_overlap and state.pair.adjust is not None:  # ADJUST may have moved nodes
                    collectives.checkpoint(comm)
                    coords = self.current_coordinates()
        self.pairings += 1
        self._pattern_checked = False
        count, changes = (
            int(v) for v in comm.allreduce(np.array([self.num_springs, self.face_changes]))
        )
        self.total_springs = count
        if self.iteration >= 1 and changes:
            logger.info(" Number of contact spring elements=%d (%d changed face)", count, changes)
        else:
            logger.info(" Number of contact spring elements=%d", count)
        for callback in self.pairing_callbacks:
            callback(self)
        return count

    def _pair_one(self, state: PairState, coords: np.ndarray, record_overlap: bool) -> None:
        empty = np.empty(0, dtype=np.int64)
        if not state.pair.active:
            state.spring_slave, state.spring_face, state.spring_area, state.xi = (
                empty,
                empty,
                np.empty(0),
                None,
            )
            state.was_active = False
            return
        if not state.was_active:  # reactivated: a fresh friction history (ccx keeps the old one)
            if self.reset_friction_on_separation:
                state.friction.reset()
            state.was_active = True
        previous = np.full(state.slave.nodes.size, -1, dtype=np.int64)
        previous[state.spring_slave] = state.spring_face
        found, face, areas, evaluation = self._search(state, coords, previous)
        if record_overlap and state.pair.adjust is not None:
            collectives.checkpoint(self.u.function_space.mesh.comm)  # before ADJUST's collectives
        if (
            record_overlap
            and state.pair.adjust is not None
            and self._adjust(state, found, evaluation)
        ):
            coords = self.current_coordinates()
            found, face, areas, evaluation = self._search(state, coords, previous)
        state.found_face = face
        gap = evaluation.gap
        if record_overlap:
            state.overlap[found] = np.minimum(gap, 0.0)
        create = self._creates_spring(state, found, gap, areas)
        state.spring_slave = found[create]
        state.spring_face = face[found][create].astype(np.int64)
        state.spring_area = areas[found][
            create
        ]  # 0 = no slave face: springs.py applies the fallback
        state.xi = evaluation.xi[create]
        if state.pair.interaction.friction is not None:
            fresh = state.friction.fresh(state.spring_slave)
            if np.any(fresh):  # anchor at the increment start (docs/method.md §11.3)
                u = self._increment_start_u
                nodes = state.element_nodes[fresh]
                phi = evaluation.phi[create][fresh]
                a = u[nodes[:, -1]] - np.einsum("nj,nji->ni", phi, u[nodes[:, :-1]])
                state.friction.anchor(state.spring_slave[fresh], a)
        current = np.full(state.slave.nodes.size, -1, dtype=np.int64)
        current[state.spring_slave] = state.spring_face
        state.face_changes = int(
            np.count_nonzero((previous >= 0) & (current >= 0) & (previous != current))
        )

    def _search(
        self, state: PairState, coords: np.ndarray, previous: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, SpringEvaluation]:
        """Master face of every slave node at ``coords`` (``previous``: current face or -1).

        Returns the slave indices with a face, the face of every slave node (-1: none), the spring
        areas of all slave nodes, and the springs' kinematics (no tangent) of the found nodes.
        """
        comm = self.u.function_space.mesh.comm
        areas = _slave_areas(state.slave, coords)
        if isinstance(state.master, master_exchange.MasterPatch):
            collectives.checkpoint(comm)  # the patch's update is collective (§14.4)
        state.master.update(coords)
        points = coords[state.slave.nodes]
        tolerances = np.where(areas > 0, SEARCH_TOLERANCE * np.sqrt(areas), 0.0)
        start, frame = None, None
        if self.walk_from_previous_face:
            collectives.checkpoint(comm)  # the tie frame sums over the processes
            start, frame = previous, self._tie_frame(state, points, areas)
        options = {"tie_frame": frame, "ccx_ties": not self.walk_from_previous_face}
        face = state.master.locate(
            points, tolerances, max_depth=self.max_depth, start_faces=start, **options
        )
        while master_exchange.enlarge(self, state, face):  # a patch too small somewhere (§14.8)
            coords = self.current_coordinates()
            state.master.update(coords)
            face = state.master.locate(
                points, tolerances, max_depth=self.max_depth, start_faces=start, **options
            )
        found = np.flatnonzero(face >= 0)
        evaluation = spring_evaluator(state.master)(
            state.master_faces.face_type,
            coords[state.master_faces.faces[face[found]]],
            points[found],
            areas[found],
            state.pair.interaction.law,
            tangent=False,
            xi0=self._previous_xi(state, found, face),
        )
        return found, face, areas, evaluation

    def _tie_frame(
        self, state: PairState, points: np.ndarray, areas: np.ndarray
    ) -> TieFrame | None:
        """Frame of master surface and slave nodes deciding search ties (docs/method.md §3.2).

        Collective: the slave nodes' moments are summed over the processes.
        """
        if not isinstance(state.master, (MasterSurface, master_exchange.MasterPatch)):
            return None  # a rigid master: one face, no ties
        origin, moments = state.master.surface_moments()
        slave = point_moments(points, areas, origin)
        comm = self.u.function_space.mesh.comm
        return frame_from_moments(moments + comm.allreduce(slave, op=MPI.SUM), origin)

    def _adjust(self, state: PairState, found: np.ndarray, evaluation: SpringEvaluation) -> int:
        """ADJUST: move the selected slave nodes onto the master (docs/method.md §11.5)."""
        adjust = state.pair.adjust
        in_set = None
        if state.adjust_nodes is not None:
            in_set = np.isin(state.slave.nodes[found], state.adjust_nodes)
        move = adjusted_nodes(evaluation.gap, None if in_set is not None else float(adjust), in_set)
        count = self.u.function_space.mesh.comm.allreduce(int(np.count_nonzero(move)))
        if count:  # on every process: the moves reach ghost and halo copies (§14.6)
            delta = -evaluation.gap[move, None] * evaluation.normal[move]
            move_reference_nodes(
                self.u.function_space,
                self._reference,
                state.slave.nodes[found[move]],
                delta,
                self.halo,
            )
            logger.info(" ADJUST: %d slave node(s) moved onto the master", count)
        return count

    def _creates_spring(
        self, state: PairState, found: np.ndarray, gap: np.ndarray, areas: np.ndarray
    ) -> np.ndarray:
        """Which of the found slave nodes get a spring: effective gap within the law's cutoff."""
        cutoff = state.pair.interaction.law.cutoff(areas[found])
        return gap - self._gap_shift(state, found) <= cutoff

    def unpaired_contacts(self) -> int:
        """Slave nodes that a pairing now would give a spring but that have none. Collective.

        For example nodes that penetrated after the pairing froze at iteration 8.
        """
        coords = self.current_coordinates()
        count = 0
        comm = self.u.function_space.mesh.comm
        with collectives.collective_errors(comm):
            for state in self.states:
                if not state.pair.active:
                    continue
                current = np.full(state.slave.nodes.size, -1, dtype=np.int64)
                current[state.spring_slave] = state.spring_face
                found, _, areas, evaluation = self._search(state, coords, current)
                create = self._creates_spring(state, found, evaluation.gap, areas)
                count += int(np.count_nonzero(create & (current[found] < 0)))
        return comm.allreduce(count)

    @staticmethod
    def _previous_xi(state: PairState, found: np.ndarray, face: np.ndarray) -> np.ndarray:
        """Projection start points: the last one where a node keeps its face, else the centre."""
        xi0 = np.tile(state.master_faces.face_type.center, (found.size, 1))
        if state.xi is not None and state.num_springs:
            previous_face = np.full(state.slave.nodes.size, -1, dtype=np.int64)
            previous_face[state.spring_slave] = state.spring_face
            previous_xi = np.zeros((state.slave.nodes.size, 2))
            previous_xi[state.spring_slave] = state.xi
            same = previous_face[found] == face[found]
            xi0[same] = previous_xi[found[same]]
        return xi0

    def _gap_shift(self, state: PairState, slave_index: np.ndarray) -> np.ndarray | float:
        """g0 (1 - tau) in static steps, 0 otherwise (docs/method.md §3.5, §11.6)."""
        if not self.static:
            return 0.0
        return state.overlap[slave_index] * (1.0 - self.time_fraction)

    # -- springs -----------------------------------------------------------------------------------

    def evaluate(self, *, tangent: bool = True) -> list[SpringBlocks]:
        """Evaluate every spring at the current displacement; returns the blocks to assemble."""
        coords = self.current_coordinates()
        blocks = []
        symmetric = self.symmetric and not self.has_friction
        for state in self.states:
            nodes = state.element_nodes
            friction = self._friction_input(state, coords, nodes)
            if self.linearize_area:  # areas follow the deformation between pairings too
                areas = _slave_areas(state.slave, coords)
                state.spring_area = areas[state.spring_slave]
            ev = spring_evaluator(state.master)(
                state.master_faces.face_type,
                coords[nodes[:, :-1]],
                coords[nodes[:, -1]],
                state.spring_area,
                self._tangent_law(state.pair.interaction.law),
                gap_shift=self._gap_shift(state, state.spring_slave),
                xi0=state.xi,
                tangent=tangent,
                symmetric=symmetric,
                friction=friction,
            )
            state.evaluation = ev
            state.xi = ev.xi
            if ev.tangential is not None:
                tf = ev.tangential
                state.friction.store(state.spring_slave, tf.a, tf.t, tf.slip)
            blocks.append(
                SpringBlocks(
                    nodes,
                    nodes,
                    ev.stiffness,
                    ev.forces.reshape(nodes.shape[0], 3 * nodes.shape[1]),
                )
            )
            if tangent and self.linearize_area:
                blocks.append(self._area_block(state, coords))
        return blocks

    def _tangent_law(self, law: PressureOverclosureLaw) -> PressureOverclosureLaw:
        """The law whose slope the tangent takes (``contact_start_slope``, docs/method.md §7.1)."""
        return start_law(law) if self.contact_start_slope and self.iteration == 0 else law

    def _friction_input(
        self, state: PairState, coords: np.ndarray, nodes: np.ndarray
    ) -> FrictionInput | None:
        """Friction state and parameters of the pair's springs, None without friction."""
        friction = state.pair.interaction.friction
        if friction is None:
            return None
        displacements = (coords - self._reference)[nodes]
        return FrictionInput(
            displacements,
            *state.friction.start_values(state.spring_slave),
            mu=friction.mu,
            stick_slope=friction.stick_slope,
            in_tension=self.friction_in_tension,
            tangent_mode=self.friction_tangent,
        )

    def _area_block(
        self, state: PairState, coords: np.ndarray, *, values: bool = True
    ) -> SpringBlocks:
        """Tangent of F_N = A_p p(d) with respect to the slave-face nodes around p (dA_p/du)."""
        faces = state.slave.faces
        slave_index, node, gradient = spring_area_gradients(
            faces.face_type, faces.faces, coords, state.slave.nodes
        )
        spring_of_slave = np.full(state.slave.nodes.size, -1, dtype=np.int64)
        spring_of_slave[state.spring_slave] = np.arange(state.num_springs)
        spring = spring_of_slave[slave_index]
        keep = spring >= 0
        if state.slave.faceless is not None:  # no face area: the fallback, not dA/du
            keep &= ~state.slave.faceless[slave_index]
        spring, node, gradient = spring[keep], node[keep], gradient[keep]
        block_values = None
        if values:
            per_area = state.evaluation.force_per_area.reshape(
                state.num_springs, 3 * state.element_nodes.shape[1]
            )[spring]
            block_values = per_area[:, :, None] * gradient[:, None, :]
        return SpringBlocks(
            state.element_nodes[spring], node[:, None].astype(np.int64), block_values
        )

    def ensure_matrix(self) -> PETSc.Mat:
        """The Jacobian matrix, recreated when the current springs need couplings it lacks."""
        blocks = [SpringBlocks(s.element_nodes, s.element_nodes) for s in self.states]
        if self.linearize_area:
            coords = self.current_coordinates()
            blocks += [self._area_block(s, coords, values=False) for s in self.states]
        if self.matrix is None or not self.assembler.has_pattern(blocks):
            if self.matrix is not None:
                self.matrix.destroy()
            comm = self.u.function_space.mesh.comm  # a failed patch lookup fails on all (§14.4)
            reserved = collectives.collectively(comm, self._reserved_blocks)
            self.matrix = self.assembler.create_matrix(blocks + reserved)
        self._pattern_checked = True
        return self.matrix

    def _reserved_blocks(self) -> list[SpringBlocks]:
        """Couplings a new matrix reserves beyond the current springs.

        Every slave node that the last pairing located, with the faces around its face, so that
        nodes moving to a neighbouring face or coming into contact need no new pattern (and no
        new symbolic factorization).
        """
        blocks = []
        for state in self.states:
            if state.found_face is None:
                continue
            located = np.flatnonzero(state.found_face >= 0)
            which, patch = state.master.face_patches(state.found_face[located])
            nodes = np.hstack(
                [state.master_faces.faces[patch], state.slave.nodes[located[which]][:, None]]
            )
            blocks.append(SpringBlocks(nodes, nodes))
        return blocks

    # -- dolfinx callbacks -------------------------------------------------------------------------
    #
    # CalculiX's order (docs/method.md §3.1, §7.1): Newton iteration k >= 2 starts with a re-pairing
    # (k <= 8), assembles and solves with it, and the convergence check after the update uses that
    # same pairing. dolfinx calls form -> F -> (convergence check) -> J -> solve, so the re-pairing
    # happens in J, which then re-assembles the residual vector last given to F (the right-hand side
    # of the coming solve).

    def form(self, x: PETSc.Vec) -> None:
        """Before F: update ghost values and evaluate the springs of the current pairing."""
        if self.elimination is not None:  # before the ghost update: ghosts get the new values
            # Prescribed values first: the reduced Jacobian cannot carry their lifting through
            # the constraints (C3D20's centres move with the prescribed nodes, §13.1, §13.5).
            dolfinx.fem.petsc.set_bc(x, self.bcs)
            self.elimination.back_substitute(x)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self._blocks = self.evaluate(tangent=True)

    def F(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Assemble the bulk residual plus the spring forces into ``b``."""
        self._residual_vector = b
        self.assemble_residual(x, b)

    def assemble_residual(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """The residual at ``x`` with the springs last evaluated by :meth:`form` into ``b``."""
        with b.localForm() as b_local:
            b_local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.L)
        dolfinx.fem.petsc.apply_lifting(b, [self.a], [self.bcs], [x], -1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.assembler.add_to_vector(b, self._blocks)
        if self.nodal_loads is not None:
            b.axpy(-1.0, compat.petsc_vector(self.nodal_loads))
        for term in self.extra_terms:
            term.add_to_residual(x, b)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)
        if self.elimination is not None:
            self.elimination.reduce_vector(
                b, lambda r: dolfinx.fem.petsc.set_bc(r, self.bcs, x, -1.0)
            )

    def J(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """Start Newton iteration ``iteration``: re-pair on schedule, assemble the Jacobian.

        A re-pairing re-assembles the residual vector too.
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
            if self._residual_vector is not None:
                self.F(x, self._residual_vector)
        pattern = (self.assembler.pattern_merges, self.assembler.matrix_rebuilds)
        self.bulk_jacobian.assemble(A, self.a, self.bcs, pattern)
        self.assembler.add_to_matrix(A, self._blocks, check_pattern=not self._pattern_checked)
        self._pattern_checked = True
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
        if self.halo is not None:
            self.halo.destroy()

    def __enter__(self) -> ContactProblem:
        return self

    def __exit__(self, *args: object) -> None:
        self.destroy()

    def set_bcs(self, bcs: typing.Sequence[compat.DirichletBC]) -> None:
        """Replace the Dirichlet conditions (e.g. between steps).

        Contact entries skip the new constrained dofs.
        """
        self.bcs = list(bcs)
        self.assembler.set_bcs(self.bcs)
        self._eliminate()


def _slave_areas(slave: SlaveSurface, coords: np.ndarray) -> np.ndarray:
    """Spring areas of the slave nodes (0 for ``faceless`` nodes: the fallback applies)."""
    faces = slave.faces
    areas = spring_areas(faces.face_type, faces.faces, coords, slave.nodes)
    if slave.faceless is not None:
        areas[slave.faceless] = 0.0
    return areas


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
