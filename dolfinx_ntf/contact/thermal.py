"""Heat conduction with heat flow across the contact springs: :class:`ThermalContactProblem`.

docs/method.md §20. The temperature ``T`` lives in a scalar space on the mesh of the displacement
``u`` of a :class:`~dolfinx_ntf.ContactProblem`, numbered like ``u``'s nodes (a scalar Lagrange
space of the same degree). Every spring of the mechanical problem's current pairing carries the heat
flow ``q = A h(p, T_mean) (T_m − T_s)`` of CalculiX's ``*GAP CONDUCTANCE``
(:mod:`~dolfinx_ntf.kernels.gap_conductance`), added to the user's UFL heat residual and its
Jacobian through a :class:`~dolfinx_ntf.contact.assembly.ContactAssembler` of the temperature space:
the mechanical springs' machinery with block size 1. The springs (their nodes, projection points,
areas and pressures) are the mechanical problem's at its current displacement; the thermal problem
holds ``u`` fixed (the staggered scheme of :func:`~dolfinx_ntf.solvers.staggered.solve_staggered`).

The class has the :class:`~dolfinx_ntf.solvers.newton_loop.NonlinearSystem` role (``a``, ``L``,
``form``, ``F``, ``J``), so :class:`~dolfinx_ntf.NewtonSolver` solves it.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.assembly import ContactAssembler, SpringBlocks
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.fem.constraints import ConstraintElimination, LinearConstraintBlock
from dolfinx_ntf.fem.discrete_springs import GlobalBlocks
from dolfinx_ntf.kernels.gap_conductance import (
    GapConductance,
    ThermalSpringEvaluation,
    evaluate_thermal_springs,
)
from dolfinx_ntf.kernels.laws import LinearLaw
from dolfinx_ntf.kernels.rigid import RigidSurface
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.parallel.global_constraints import distributed_elimination

__all__ = ["HeatElementTerm", "ThermalContactProblem"]


class HeatElementTerm(typing.Protocol):
    """Element blocks added to the heat residual and Jacobian, in the global numbering.

    For example film conditions on faces the mesh has no ``ds`` for (C3D15's, docs/method.md
    §39); see ``ThermalContactProblem.element_terms``. Their couplings must be in the
    matrix pattern (nodes of one cell).
    """

    def evaluate(self, x: PETSc.Vec) -> GlobalBlocks:
        """This process's blocks at the temperature ``x`` (ghosts updated); -1 skips a dof."""


class ThermalContactProblem:
    """Nonlinear heat problem ``F_T(T) + q_contact(T; u) = 0`` on the springs of ``contact``.

    Args:
        F: The user's UFL heat residual in ``T`` (conduction, sources, film conditions; for a
            transient step the backward-Euler capacity term ``rho c (T - T_old)/dt v dx``).
        T: The temperature, a scalar Lagrange function on ``contact.u``'s mesh and degree.
        contact: The mechanical problem whose springs conduct heat.
        conductances: One :class:`~dolfinx_ntf.GapConductance` per pair of ``contact`` (in its
            order), or one for all pairs.
        bcs: Dirichlet conditions on ``T``'s space.
        J: UFL Jacobian (derived from ``F`` when omitted).
        conductance_pressure: The pressure the conductance table is looked up at: ``"contact"``
            (the spring's contact pressure ``F_N/A``, default) or ``"ccx"`` (CalculiX 2.20's
            thermal spring: the slope ``K`` of a LINEAR law, whatever the contact pressure;
            docs/method.md §20.1; other laws are refused, their ccx value is not measured).
        constraints: Constraint blocks on ``T``'s dofs (``block_size=1``), eliminated as the
            displacement's (docs/method.md §13.1): C3D15's face centres (§39). The Jacobian the
            linear solver needs is then :attr:`reduced_matrix`.
        form_compiler_options, jit_options: Passed to dolfinx's form compiler and JIT.
    """

    def __init__(
        self,
        F: ufl.form.Form,
        T: dolfinx.fem.Function,
        contact: ContactProblem,
        conductances: GapConductance | typing.Sequence[GapConductance],
        bcs: typing.Sequence[compat.DirichletBC] = (),
        J: ufl.form.Form | None = None,
        *,
        conductance_pressure: str = "contact",
        constraints: typing.Sequence[LinearConstraintBlock] = (),
        form_compiler_options: dict | None = None,
        jit_options: dict | None = None,
    ) -> None:
        owner = "ThermalContactProblem"
        validation.check_type(contact, ContactProblem, f"{owner}: contact")
        num_pairs = len(contact.states)
        if isinstance(conductances, GapConductance):
            conductances = [conductances] * num_pairs
        conductances = list(conductances)
        if len(conductances) != num_pairs:
            raise ValueError(
                f"{owner}: {len(conductances)} conductances for {num_pairs} contact pairs; give "
                "one per pair (in the order of the pairs) or one for all"
            )
        for i, h in enumerate(conductances):
            validation.check_type(h, GapConductance, f"{owner}: conductances[{i}]")
        if conductance_pressure not in ("contact", "ccx"):
            raise ValueError(
                f"{owner}: conductance_pressure must be 'contact' or 'ccx', got "
                f"{conductance_pressure!r}"
            )
        if conductance_pressure == "ccx":
            other = [
                f"{s.pair.name or i} ({type(s.pair.interaction.law).__name__})"
                for i, s in enumerate(contact.states)
                if type(s.pair.interaction.law) is not LinearLaw
            ]
            if other:
                raise NotImplementedError(
                    f"{owner}: conductance_pressure='ccx' is known for LinearLaw only; pair(s) "
                    f"{other} have another law"
                )
        #: ``"contact"`` or ``"ccx"``: the pressure the conductance tables are looked up at.
        self.conductance_pressure = conductance_pressure
        Q = T.function_space
        collectives.collectively(contact.u.function_space.mesh.comm, _check_space, T, contact.u)
        rigid = [
            s.pair.name or str(i)
            for i, s in enumerate(contact.states)
            if isinstance(s.pair.master, RigidSurface)
        ]
        if rigid:
            raise NotImplementedError(
                f"{owner}: pair(s) {rigid} have a rigid master surface, which has no temperature"
            )
        validation.check_residual(F, T, owner, J)
        options = compat.jit_keywords(form_compiler_options, jit_options)
        #: The UFL heat residual.
        self.residual_form = F
        self._L = dolfinx.fem.form(F, **options)
        self._a = dolfinx.fem.form(
            ufl.derivative(F, T, ufl.TrialFunction(Q)) if J is None else J, **options
        )
        self.T = T
        self.contact = contact
        self.conductances = conductances
        self.bcs = validation.check_bcs(bcs, owner)
        self.assembler = ContactAssembler(Q, self._a, self.bcs)
        self._halo_nodes = 0
        self._follow_halo()
        self.matrix: PETSc.Mat | None = None
        self._blocks: list[SpringBlocks] = []
        #: Heat flow into the slave node of every spring of every pair at the last evaluation
        #: (positive when the master side is hotter), per pair in ``contact``'s order.
        self.heat_flows: list[np.ndarray] = []
        #: ∂(heat flows)/∂u of the springs at the last evaluation with ``coupling``: blocks of
        #: (n+1, 3(n+1)) per spring (docs/method.md §20.2).
        self.coupling_blocks: list[SpringBlocks] = []
        #: The thermal springs of every pair at the last evaluation (None where a pair has none).
        self.evaluations: list[ThermalSpringEvaluation | None] = []
        #: The elimination of ``constraints`` (None without any, on every process).
        self.elimination = _elimination(Q, list(constraints), self.bcs)
        #: The reduced Jacobian ``T'^T J T'`` of the last :meth:`J` with constraints, else None.
        self.reduced_matrix: PETSc.Mat | None = None
        #: Heat flows into the nodes (a function of ``T``'s space, e.g. CalculiX's ``*CFLUX``),
        #: subtracted from the residual; None for none.
        self.nodal_loads: dolfinx.fem.Function | None = None
        #: Element blocks added to the residual and the Jacobian (e.g. films, §39).
        self.element_terms: list[HeatElementTerm] = []
        self._element_blocks: list[GlobalBlocks] = []

    @property
    def L(self) -> compat.Form:
        """The compiled residual form ``F``."""
        return self._L

    @property
    def a(self) -> compat.Form:
        """The compiled Jacobian form."""
        return self._a

    def temperatures(self) -> np.ndarray:
        """``T`` at the contact nodes (local with ghosts, then the halo's). Collective."""
        halo = self.contact.halo
        return self.T.x.array if halo is None else halo.field(self.T)[:, 0]

    def _follow_halo(self) -> None:
        """Number the contact halo's nodes in the temperature space too, also after it grew.

        The halo grows when a master patch does (docs/method.md §14.8). Collective.
        """
        halo = self.contact.halo
        if halo is None:
            return
        grown = halo.global_nodes.size != self._halo_nodes
        if halo.comm.allreduce(grown, op=MPI.LOR):
            self.assembler.extend(halo, self.T)
            self._halo_nodes = halo.global_nodes.size

    def evaluate(
        self, *, tangent: bool = True, coupling: bool = False, mechanics: bool = True
    ) -> list[SpringBlocks]:
        """The thermal springs at the current ``T`` and the mechanical springs at ``u``. Collective.

        Args:
            tangent: Also the temperature tangent.
            coupling: Also the blocks of the heat flows' derivatives with respect to the
                displacement (:attr:`coupling_blocks`; needs the mechanical tangent).
            mechanics: Re-evaluate the mechanical springs at the current displacement first (so
                that projection points, areas and pressures belong to the current pairing); a
                coupled solve that has just evaluated them passes False.
        """
        if mechanics:
            self.contact.evaluate(tangent=coupling)
        self._follow_halo()
        temperatures = self.temperatures()
        blocks, self.heat_flows, self.coupling_blocks, self.evaluations = [], [], [], []
        for state, conductance in zip(self.contact.states, self.conductances):
            ev = state.evaluation
            if state.num_springs == 0 or ev is None:
                self.heat_flows.append(np.zeros(0))
                self.evaluations.append(None)
                continue
            if coupling and ev.dxi is None:
                raise RuntimeError(
                    "ThermalContactProblem.evaluate: the coupling needs the mechanical springs "
                    "evaluated with their tangent"
                )
            nodes = state.element_nodes
            if self.conductance_pressure == "ccx":  # ccx 2.20: the slope, constant (§20.1)
                pressure = np.full(state.num_springs, state.pair.interaction.law.slope)
                dpressure = None if ev.dpressure is None else np.zeros_like(ev.dpressure)
            else:
                pressure = np.divide(
                    ev.normal_force, ev.area, out=np.zeros_like(ev.area), where=ev.area > 0
                )
                dpressure = ev.dpressure
            th = evaluate_thermal_springs(
                state.master_faces.face_type,
                ev.xi,
                temperatures[nodes],
                ev.area,
                pressure,
                conductance,
                tangent=tangent,
                dxi=ev.dxi if coupling else None,
                dpressure=dpressure if coupling else None,
            )
            self.heat_flows.append(th.flow)
            self.evaluations.append(th)
            blocks.append(SpringBlocks(nodes, nodes, th.jacobian, th.residual))
            if coupling:
                self.coupling_blocks.append(SpringBlocks(nodes, nodes, th.coupling))
        return blocks

    def ensure_matrix(self) -> PETSc.Mat:
        """The Jacobian matrix, recreated when the current springs need couplings it lacks."""
        blocks = [SpringBlocks(s.element_nodes, s.element_nodes) for s in self.contact.states]
        if self.matrix is None or not self.assembler.has_pattern(blocks):
            if self.matrix is not None:
                self.matrix.destroy()
            self.matrix = self.assembler.create_matrix(blocks)
        return self.matrix

    # -- NonlinearSystem callbacks -----------------------------------------------------------------

    def form(self, x: PETSc.Vec, *, coupling: bool = False, mechanics: bool = True) -> None:
        """Before F: update the ghost values of ``x`` and evaluate the thermal springs.

        ``coupling`` and ``mechanics`` as for :meth:`evaluate`. With constraints the prescribed
        values are set into ``x`` and its dependent dofs back-substituted first (§13.1).
        """
        if self.elimination is not None:  # before the ghost update: ghosts get the new values
            dolfinx.fem.petsc.set_bc(x, self.bcs)
            self.elimination.back_substitute(x)
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self._blocks = self.evaluate(tangent=True, coupling=coupling, mechanics=mechanics)
        self._element_blocks = [term.evaluate(x) for term in self.element_terms]

    def F(self, x: PETSc.Vec, b: PETSc.Vec) -> None:
        """Assemble the bulk heat residual plus the springs' heat flows at ``x`` into ``b``.

        Minus :attr:`nodal_loads` where given, plus :attr:`element_terms`.
        """
        with b.localForm() as b_local:
            b_local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, self.L)
        dolfinx.fem.petsc.apply_lifting(b, [self.a], [self.bcs], [x], -1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self.assembler.add_to_vector(b, self._blocks)
        if self.nodal_loads is not None:
            b.axpy(-1.0, compat.petsc_vector(self.nodal_loads))
        if self._element_blocks:
            self.assembler.add_global_to_vector(b, self._element_blocks)
        dolfinx.fem.petsc.set_bc(b, self.bcs, x, -1.0)
        if self.elimination is not None:
            self.elimination.reduce_vector(
                b, lambda r: dolfinx.fem.petsc.set_bc(r, self.bcs, x, -1.0)
            )

    def J(self, x: PETSc.Vec, A: PETSc.Mat) -> None:
        """The Jacobian at ``x`` (bulk, springs' exact temperature tangent) into ``A``.

        With constraints also its reduction, :attr:`reduced_matrix`.
        """
        A.zeroEntries()
        dolfinx.fem.petsc.assemble_matrix(A, self.a, self.bcs)
        A.assemble()
        self.assembler.add_to_matrix(A, self._blocks)
        A.assemble()
        if self._element_blocks:
            self.assembler.add_global_to_matrix(A, self._element_blocks)
            A.assemble()
        if self.elimination is not None:
            key = (A.handle, self.assembler.pattern_merges, self.assembler.matrix_rebuilds)
            self.reduced_matrix = self.elimination.reduce_matrix(A, key)

    def destroy(self) -> None:
        """Destroy the PETSc matrix the problem owns. Collective."""
        if self.matrix is not None:
            self.matrix.destroy()
            self.matrix = None
        if self.elimination is not None:
            self.elimination.destroy()
            self.elimination, self.reduced_matrix = None, None


def _elimination(
    Q: dolfinx.fem.FunctionSpace,
    constraints: list[LinearConstraintBlock],
    bcs: typing.Sequence[compat.DirichletBC],
) -> ConstraintElimination | None:
    """The elimination of the constraints on ``T``'s space (None if no process has any).

    Collective. Prescribed dofs are never dependent (docs/method.md §13.1).
    """
    comm = Q.mesh.comm
    if not comm.allreduce(len(constraints), op=MPI.MAX):
        return None

    def check() -> None:
        for c in constraints:
            validation.check_type(c, LinearConstraintBlock, "ThermalContactProblem: constraints")
            if c.block_size != 1:
                raise ValueError(
                    f"ThermalContactProblem: constraint block {c.name!r} has block size "
                    f"{c.block_size}; T's space is scalar (block size 1)"
                )

    collectives.collectively(comm, check)
    prescribed = [bc.dof_indices()[0] for bc in bcs]
    prescribed = np.concatenate(prescribed) if prescribed else np.zeros(0, np.int64)
    if comm.size > 1:  # every process's constraints, in the global numbering (§14.6)
        return collectives.collectively(comm, distributed_elimination, Q, constraints, prescribed)
    return ConstraintElimination(Q.dofmap.index_map.size_local, constraints, prescribed, comm)


def _check_space(T: object, u: dolfinx.fem.Function) -> None:
    """Raise ``ValueError`` unless ``T``'s scalar space numbers its nodes like ``u``'s space."""
    owner = "ThermalContactProblem"
    validation.check_type(T, dolfinx.fem.Function, f"{owner}: T")
    Q, V = T.function_space, u.function_space
    if Q.mesh is not V.mesh or Q.dofmap.index_map_bs != 1:
        raise ValueError(f"{owner}: T must be a scalar function on the displacement's mesh")
    if V.mesh.topology.dim != 3:
        raise NotImplementedError(f"{owner}: thermal contact is 3D only for now")
    same = (
        Q.dofmap.index_map.size_local == V.dofmap.index_map.size_local
        and Q.dofmap.index_map.num_ghosts == V.dofmap.index_map.num_ghosts
        and np.array_equal(compat.cell_dofs(Q), compat.cell_dofs(V))
    )
    if not same:
        raise ValueError(
            f"{owner}: T's space must number its nodes like the displacement's (a scalar "
            "Lagrange space of the same degree on the same mesh)"
        )
