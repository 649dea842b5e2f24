"""The dolfinx model of a deck (:class:`CalculixModel`) and ``build_model``, which assembles it.

``build_model`` wires the pieces of the package's other modules (mesh and numbering maps,
surfaces, bulk stresses, load schedules, ``*EQUATION`` constraints, contact pairs) into the UFL
residual: the bulk stress integrated like ccx (C3D8 2x2x2 Gauss, C3D4 one point, C3D10 four
points, C3D20 3x3x3, C3D20R 2x2x2) and the ``*DLOAD`` pressures on the reference faces, or as
follower loads ``p J F^-T N`` with ``NLGEOM``. :class:`CalculixModel` evaluates the loads of a
step at any time and creates the contact problem.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactPair, ContactProblem
from dolfinx_ntf.fem.constraints import LinearConstraint, LinearConstraintBlock, num_equations
from dolfinx_ntf.fem.discrete_springs import DiscreteSprings
from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
from dolfinx_ntf.fem.follower_pressure import FollowerPressure, PressureFaces
from dolfinx_ntf.fem.incompatible_modes import IncompatibleModes
from dolfinx_ntf.fem.plane_sections import PlaneSections
from dolfinx_ntf.fem.plasticity import J2Plasticity
from dolfinx_ntf.fem.serendipity import serendipity_constraints, trilinear_constraints
from dolfinx_ntf.fem.serendipity_quad import quad_serendipity_constraints
from dolfinx_ntf.fem.serendipity_wedge import wedge_serendipity_constraints
from dolfinx_ntf.fem.surfaces import FaceNodesSurface, FacetSurface, NodeSurface
from dolfinx_ntf.parallel import collectives
from dolfinx_ntf.parallel.global_constraints import global_constraint_block, global_constraints

from ..deck import Deck, ElementBlock, not_supported
from ..elements import ElementType
from .bulk import density, lame, plane_stress_factor, stresses
from .c3d15 import C3D15Pressures, c3d15_metadata, check_c3d15_deck
from .carriers import carried_nodes, carrier_dofs
from .contact import contact_pairs
from .equations import FreeReference, equation_constraints
from .loads import Schedule, StepLoads, schedules
from .mesh import create_mesh, element_block, element_models, mesh_maps, numbering
from .mixed import CellMeasures, check_mixed_deck, mixed_hexahedra
from .plane import (
    check_two_d_deck,
    plane_kinematics,
    plane_sections,
    printed_scale,
    section_thickness,
    volume_weight,
)
from .plasticity import check_plastic_deck, plastic_laws
from .springs import check_springs, deck_springs
from .surfaces import deck_surfaces
from .thermal import ThermalModel, is_thermal, thermal_model
from .ties import tie_constraints
from .wedge_rules import wedge_rules

__all__ = ["CalculixModel", "build_model"]


@dataclass(eq=False)
class CalculixModel:
    """dolfinx objects of a CalculiX deck (see the module docstring).

    Attributes:
        deck: The parsed deck.
        element_type: The deck's element type.
        mesh, V, u: Mesh, vector displacement space (degree of the element) and displacement.
        node_dof: ``(N,)`` local block dof of each deck node (rows of ``deck.node_ids``), -1 for
            nodes in no element (and, on several processes, nodes this process does not hold).
        dof_node: ccx node number of each local block dof.
        node_vertex: ``(N,)`` local mesh vertex of each deck node, -1 for midside or unused nodes.
        element_cell: ``(E,)`` local cell of each element (rows of the deck's element block), -1
            for elements this process does not hold.
        cell_element: ccx element number of each local cell.
        surfaces: dolfinx surface of each ccx surface name.
        surface_tags: facet tags (value 1) of each element-face surface.
        surface_faces: per element-face surface, ``(facets, nodes)``: its sorted local facets and
            their ccx node numbers in ccx face order (for contact-element output).
        pairs: contact pairs in deck order.
        mu, lmbda: Lamé parameters per cell (DG0).
        nlgeom: Constant switching the kinematics (0 small strain, 1 St.Venant-Kirchhoff) when the
            deck has both kinds of steps, else None (the forms then hold one kind only).
        dx: Volume measure with ccx's quadrature.
        first_piola: First Piola-Kirchhoff stress (the small-strain stress when ``nlgeom`` is 0).
        cauchy: Cauchy stress.
        residual: Bulk residual ``f_int - f_ext(pressures)`` (without concentrated forces).
        nodal_loads: Concentrated forces (``*CLOAD``) on ``V``.
        pressures: One Constant per pressure group; ``pressure_tags`` marks each group's facets
            with value ``group + 1``.
        steps: Load schedule of every step.
        amplitude_names: Amplitude names by index.
        constraints: The ``*EQUATION`` constraints on ``V``'s dofs (docs/method.md §13.1), then
            for C3D20/C3D20R the serendipity constraints of the face and cell centres (§13.5), then
            the ``*TIE`` blocks (surface ties and cyclic symmetry, §19).
        reference_terms: ``(constraint, keys, coefficients)`` of the ``*EQUATION`` terms on nodes
            in no element, whose prescribed values move to the constraint's right-hand side.
        free_references: Components of nodes in no element without ``*BOUNDARY``, eliminated.
        springs: The spring elements (SPRINGA, SPRING1, SPRING2), one
            :class:`~dolfinx_ntf.DiscreteSprings` per ``*SPRING`` card (docs/method.md §18.3).
        internal_force: The bulk internal force form ``f_int`` (test function on ``V``), whose
            element vectors make the ``RF`` output.
        printed_force: The internal force whose element vectors ccx's ``RF`` prints, when it is
            not ``internal_force``: CAX decks leave out the hoop term of the radial force, as the
            sum of ccx's expanded nodes' forces does (docs/method.md §23); else None.
        printed_scale: Factor from the model's forces and spring energies to those ccx prints
            (1; CAX decks 1/180: ccx prints its 2-degree sector's, docs/method.md §23).
        thermal: The temperature field of a deck with coupled steps (docs/method.md §20.8), else
            None.
        incompatible_modes: C3D8I's condensed internal modes on every owned cell (an element
            term of the problem, docs/method.md §22), else None.
        plasticity: One J2 law per ``*PLASTIC`` section (the problem's history; its cells are
            left out of the elastic form, docs/method.md §21.6).
        jacobian: The bulk Jacobian when the residual has plastic terms (``ufl.derivative``
            cannot see through their stress), else None.
        axisymmetric_elements: The ccx numbers of the CAX elements (their printed stresses are
            those of ccx's sector, docs/method.md §26.4), else None.
        sections: The per-cell 2D models of a quasi-axisymmetric deck or of NLGEOM on 2D
            elements (docs/method.md §26), else None.
        spring_only_nodes: ``(k, 2)`` ccx node numbers and components whose ``RF`` is their
            contact springs' force only: the free components of the nodes of node-based slave
            surfaces of 2D elements, which ccx keeps out of its expanded elements
            (docs/method.md §26.3); else None.
        gravity: The ``*DLOAD ... GRAV`` acceleration per cell (DG0 vector; the residual holds
            ``-rho inner(g, v) dx``), or None for decks without gravity (docs/method.md §27).
        mass_dx: The measure of the mass form: C3D8's 2x2x2 Gauss points on C3D8 cells (ccx's
            C3D8 mass, measured: docs/method.md §27.4), UFL's estimate on the others.
        pressure_loads: C3D15 decks with ``*DLOAD`` pressures: ``(dofs, unit)``, the unrolled
            dofs this process holds and each pressure group's nodal forces there for a unit
            pressure, added to ``nodal_loads`` (no ``ds`` on prism meshes, docs/method.md §34);
            else None.
        follower_pressure: C3D15 decks with ``*DLOAD`` pressures and NLGEOM: the pressures on
            the current faces, an element term of the problem (§34.4); else None.
    """

    deck: Deck
    element_type: ElementType
    mesh: dolfinx.mesh.Mesh
    V: dolfinx.fem.FunctionSpace
    u: dolfinx.fem.Function
    node_dof: np.ndarray
    dof_node: np.ndarray
    node_vertex: np.ndarray
    element_cell: np.ndarray
    cell_element: np.ndarray
    surfaces: dict[str, FacetSurface | NodeSurface | FaceNodesSurface]
    surface_tags: dict[str, compat.MeshTags]
    surface_faces: dict[str, tuple[np.ndarray, np.ndarray]]
    pairs: list[ContactPair]
    mu: dolfinx.fem.Function
    lmbda: dolfinx.fem.Function
    nlgeom: dolfinx.fem.Constant | None
    dx: ufl.Measure | CellMeasures
    first_piola: ufl.core.expr.Expr
    cauchy: ufl.core.expr.Expr
    residual: ufl.Form
    nodal_loads: dolfinx.fem.Function
    pressures: list[dolfinx.fem.Constant]
    pressure_tags: compat.MeshTags | None
    steps: list[StepLoads]
    amplitude_names: list[str]
    _bc_spaces: list[tuple[dolfinx.fem.FunctionSpace, np.ndarray, dolfinx.fem.Function]] = field(
        default_factory=list, repr=False
    )
    constraints: list[LinearConstraint | LinearConstraintBlock] = field(default_factory=list)
    #: Local block dofs of the carrier cells' new points, held at zero (§29.6).
    carrier_dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    reference_terms: list[tuple[int, np.ndarray, np.ndarray]] = field(default_factory=list)
    free_references: list[FreeReference] = field(default_factory=list)
    springs: list[DiscreteSprings] = field(default_factory=list)
    internal_force: ufl.Form | None = None
    printed_force: ufl.Form | None = None
    printed_scale: float = 1.0

    @property
    def symmetric_bulk(self) -> bool:
        """Whether the bulk Jacobian is symmetric.

        Not with finite-strain plastic laws, whose algorithmic tangent ``dP/dF`` is not
        (docs/method.md §21.7), nor with C3D15's thermal strain under NLGEOM: ``P = F S(E(H - x
        I))`` is no energy's gradient (§39.1; C3D8's coupled steps factorize their own matrix).
        """
        if any(isinstance(law, FiniteStrainJ2Plasticity) for law in self.plasticity):
            return False
        thermal = self.thermal is not None and self.thermal.strain_at_points
        return not (thermal and any(step.nlgeom for step in self.deck.steps))

    @property
    def gdim(self) -> int:
        """The number of displacement components (2 for ccx's 2D elements, else 3)."""
        return int(self.mesh.geometry.dim)

    thermal: ThermalModel | None = None
    incompatible_modes: IncompatibleModes | None = None
    plasticity: list[J2Plasticity | FiniteStrainJ2Plasticity] = field(default_factory=list)
    jacobian: ufl.Form | None = None
    axisymmetric_elements: np.ndarray | None = None
    sections: PlaneSections | None = None
    spring_only_nodes: np.ndarray | None = None
    gravity: dolfinx.fem.Function | None = None
    mass_dx: ufl.Measure | CellMeasures | None = None
    pressure_loads: tuple[np.ndarray, np.ndarray] | None = None
    follower_pressure: FollowerPressure | None = None

    # -- numbering ---------------------------------------------------------------------------------

    def node_dofs(self, node_ids: np.ndarray) -> np.ndarray:
        """Local block dofs of ccx node numbers (any shape); -1 for nodes in no element."""
        return self.node_dof[self.deck.node_index(node_ids)]

    def element_cells(self, element_ids: np.ndarray) -> np.ndarray:
        """Local cells of ccx element numbers (-1 for cells of other processes)."""
        block = self.deck.elements[self.element_type.name]
        order = np.argsort(block.ids)
        ids = np.asarray(element_ids, dtype=np.int64)
        pos = np.minimum(np.searchsorted(block.ids, ids, sorter=order), block.ids.size - 1)
        rows = order[pos]
        if np.any(block.ids[rows] != ids):
            raise ValueError(
                f"element {int(ids[block.ids[rows] != ids][0])} is not defined in {self.deck.path}"
            )
        return self.element_cell[rows]

    def nodal_values(self, node_ids: np.ndarray, values: np.ndarray) -> np.ndarray:
        """Rows of a ``(num_dofs, k)`` per-dof array at ccx nodes (zeros for unused nodes)."""
        dofs = self.node_dofs(node_ids)
        out = np.zeros((dofs.size, *values.shape[1:]))
        out[dofs >= 0] = values[dofs[dofs >= 0]]
        return out

    def face_nodes_of(self, surface: str, facets: np.ndarray) -> np.ndarray:
        """Ccx node numbers (ccx face order) of local ``facets`` of an element-face surface."""
        sorted_facets, nodes = self.surface_faces[surface]
        pos = np.searchsorted(sorted_facets, facets)
        return nodes[pos]

    # -- steps -------------------------------------------------------------------------------------

    def total_time(self, step_index: int, step_time: float) -> float:
        """Total time at ``step_time`` of step ``step_index`` (0-based)."""
        return self.steps[step_index].total_time_start + step_time

    def begin_step(self, step_index: int) -> list[compat.DirichletBC]:
        """Start step ``step_index`` (0-based) from the current ``u``: kinematics and constraints.

        Prescribed displacements ramp from their value in ``u`` now. Returns the step's conditions.
        """
        loads = self.steps[step_index]
        if self.nlgeom is not None:
            self.nlgeom.value = 1.0 if loads.step.nlgeom else 0.0
        loads.bc.start = self.u.x.array[loads.bc_dofs].copy()
        bcs = []
        for component, (Vi, inverse, g) in enumerate(self._bc_spaces):
            dofs = loads.bc_dofs[loads.bc_dofs % self.gdim == component].astype(np.int32)
            if self.carrier_dofs.size:  # zero: g is set at loads.bc_dofs only
                held = self.gdim * self.carrier_dofs + component
                dofs = np.union1d(dofs, held).astype(np.int32)
            if dofs.size:
                pair = [dofs, inverse[dofs].astype(np.int32)]
                bcs.append(dolfinx.fem.dirichletbc(g, pair, self.V.sub(component)))
        return bcs

    def set_time(self, step_index: int, step_time: float, *, ramp: bool = True) -> None:
        """Set concentrated forces, pressures and prescribed displacements at ``step_time``.

        Without an amplitude they ramp linearly over the step, or (``ramp=False``, ccx's
        ``*DYNAMIC``) act in full from its start.
        """
        loads = self.steps[step_index]
        total = loads.total_time_start + step_time
        fraction = step_time / loads.period if ramp else 1.0
        self.nodal_loads.x.array[:] = 0.0
        self.nodal_loads.x.array[loads.cload_dofs] = self._evaluate(
            loads.cload, fraction, step_time, total
        )
        if self.free_references and loads.reference_force_keys.size:
            forces = self._evaluate(loads.reference_force, fraction, step_time, total)
            by_key = dict(zip(loads.reference_force_keys.tolist(), forces))
            for ref in self.free_references:  # virtual work of the force on the reference node
                if ref.key in by_key:  # at the dofs this process holds (owned and ghost)
                    dofs = 3 * self.node_dof[ref.mesh_keys // 3] + ref.mesh_keys % 3
                    held = dofs >= 0
                    np.add.at(
                        self.nodal_loads.x.array,
                        dofs[held],
                        by_key[ref.key] * ref.mesh_weights[held],
                    )
        pressure = self._evaluate(loads.pressure, fraction, step_time, total)
        for constant, value in zip(self.pressures, pressure):
            constant.value = value
        if self.pressure_loads is not None:  # C3D15: nodal forces of unit pressures (§34)
            dofs, unit = self.pressure_loads
            self.nodal_loads.x.array[dofs] += np.asarray(pressure) @ unit
        if self.gravity is not None:
            self.gravity.x.array[:] = 0.0
            if loads.gravity is not None and loads.gravity_keys.size:
                cells = compat.cell_dofs(self.gravity.function_space)[loads.gravity_keys // 3, 0]
                self.gravity.x.array[3 * cells + loads.gravity_keys % 3] = self._evaluate(
                    loads.gravity, fraction, step_time, total
                )
        values = self._evaluate(loads.bc, fraction, step_time, total)
        for component, (_, inverse, g) in enumerate(self._bc_spaces):
            mask = loads.bc_dofs % self.gdim == component
            g.x.array[inverse[loads.bc_dofs[mask]]] = values[mask]

    def reference_displacements(
        self, step_index: int, step_time: float, displacement: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Components of nodes in no element at ``step_time``: keys and values.

        Keys are ``3 node row + component``; ccx prints the values as the nodes' displacement.
        Free components are computed from ``displacement``, ``(N, 3)`` at every deck node (on
        several processes the gathered one; default this process's ``u``).
        """
        loads = self.steps[step_index]
        keys, values = np.zeros(0, np.int64), np.zeros(0)
        if loads.reference is not None and loads.reference_keys.size:
            total = loads.total_time_start + step_time
            keys = loads.reference_keys
            values = self._evaluate(loads.reference, step_time / loads.period, step_time, total)
        if not self.free_references:
            return keys, values
        known = dict(zip(keys.tolist(), values))
        if displacement is None:
            displacement = np.zeros((self.deck.node_ids.size, 3))
            held = self.node_dof >= 0
            displacement[held] = self.u.x.array.reshape(-1, 3)[self.node_dof[held]]
        free = []
        for ref in self.free_references:
            u = float(np.dot(ref.mesh_weights, displacement.ravel()[ref.mesh_keys]))
            u += sum(
                w * known.get(int(k), 0.0)
                for k, w in zip(ref.reference_keys, ref.reference_weights)
            )
            free.append((ref.key, u))
        keys = np.concatenate([keys, np.array([k for k, _ in free], dtype=np.int64)])
        values = np.concatenate([values, [v for _, v in free]])
        order = np.argsort(keys)
        return keys[order], values[order]

    def constraint_values(self, step_index: int, step_time: float) -> np.ndarray | None:
        """Right-hand sides of ``constraints`` at ``step_time``: minus the reference-node terms.

        None without reference nodes. A reference component without a prescribed value in the
        step is a ``ValueError`` (it would need a dof outside the mesh).
        """
        if not self.reference_terms:
            return None
        loads = self.steps[step_index]
        total = loads.total_time_start + step_time
        known = self._evaluate(loads.reference, step_time / loads.period, step_time, total)
        values = np.zeros(num_equations(self.constraints))
        for k, keys, coefficients in self.reference_terms:
            given = loads.reference_keys
            pos = np.minimum(np.searchsorted(given, keys), max(given.size - 1, 0))
            missing = given[pos] != keys if given.size else np.ones(keys.size, dtype=bool)
            if np.any(missing):
                key = int(keys[missing][0])
                node = int(self.deck.node_ids[key // 3])
                raise ValueError(
                    f"{self.constraints[k].name}: node {node} belongs to no element and its "
                    f"direction {key % 3 + 1} has no *BOUNDARY in step {loads.step.number}: a "
                    "free reference node is not supported (it needs a dof outside the mesh)"
                )
            values[k] = -float(np.dot(coefficients, known[pos]))
        return values

    def _evaluate(
        self, schedule: Schedule, fraction: float, step_time: float, total_time: float
    ) -> np.ndarray:
        """Values of ``schedule`` at ``fraction`` of the step (amplitudes at step or total time)."""
        value = schedule.start + (schedule.ref - schedule.start) * fraction
        for index in np.unique(schedule.amplitude[schedule.amplitude >= 0]):
            amp = self.deck.amplitudes[self.amplitude_names[index]]
            t = total_time if amp.total_time else step_time
            mask = schedule.amplitude == index
            value[mask] = schedule.ref[mask] * np.interp(t, amp.times, amp.values)
        return value

    # -- dynamics ---------------------------------------------------------------------------------

    def mass_form(self) -> ufl.Form:
        """``rho inner(w, v) dx`` with each section's ``*DENSITY`` (``mass_dx``).

        The consistent mass; C3D8 cells with their 2x2x2 Gauss points as ccx (docs/method.md
        §27.4), the other elements with UFL's estimate (exact on undistorted cells).
        """
        Q = compat.scalar_space(self.mesh, "DG", 0)
        rho = dolfinx.fem.Function(Q, name="density")
        block_ids = self.deck.elements[self.element_type.name].ids
        for section in self.deck.sections:
            density = self.deck.materials[section.material].extra.get("*DENSITY")
            if not density or len(density) != 1 or density[0][0] is None or density[0][0] <= 0.0:
                raise ValueError(
                    f"{section.location}: a *DYNAMIC step needs one positive *DENSITY in material "
                    f"{section.material} (temperature-dependent densities are not supported)"
                )
            members = np.unique(self.deck.elsets[section.elset])
            cells = self.element_cells(members[np.isin(members, block_ids)])
            cells = cells[cells >= 0]  # this process's (owned and ghost) cells
            rho.x.array[compat.cell_dofs(Q)[cells, 0]] = density[0][0]
        w, v = ufl.TrialFunction(self.V), ufl.TestFunction(self.V)
        return rho * ufl.inner(w, v) * self.mass_dx

    def initial_velocity(self) -> dolfinx.fem.Function:
        """The ``*INITIAL CONDITIONS, TYPE=VELOCITY`` of the deck as a Function (zero elsewhere)."""
        velocity = dolfinx.fem.Function(self.V, name="velocity")
        values = velocity.x.array.reshape(-1, 3)
        for condition in self.deck.initial_velocities:
            dofs = self.node_dofs(condition.nodes)
            values[dofs[dofs >= 0], condition.dof - 1] = condition.value
        velocity.x.scatter_forward()
        return velocity

    # -- problem -----------------------------------------------------------------------------------

    def create_problem(self, bcs: Sequence[compat.DirichletBC] = (), **options) -> ContactProblem:
        """The :class:`~dolfinx_ntf.ContactProblem` of the deck (bulk only without contact pairs).

        Args:
            bcs: Initial Dirichlet conditions (usually ``begin_step(0)``).
            options: :class:`~dolfinx_ntf.ContactProblem` options (``symmetric``, ``jit_options``).
        """
        options.setdefault("constraints", self.constraints)
        if self.plasticity:
            options.setdefault("J", self.jacobian)
            options.setdefault("history", self.plasticity)
        problem = ContactProblem(self.residual, self.u, self.pairs, bcs, **options)
        problem.nodal_loads = self.nodal_loads
        problem.element_terms.extend(self.springs)
        if self.incompatible_modes is not None:
            problem.element_terms.append(self.incompatible_modes)
        if self.follower_pressure is not None:
            problem.element_terms.append(self.follower_pressure)
        return problem


def check_incompatible_modes(deck: Deck) -> None:
    """Refuse what C3D8I decks cannot do yet: its modes are condensed for small strain statics.

    ``NLGEOM`` (the modes' correction is linear elasticity's), ``*FREQUENCY`` and ``*DYNAMIC``
    (ccx's modal stiffness and mass with the modes are not measured), naming the step's line.
    """
    for step in deck.steps:
        what = (
            "NLGEOM"
            if step.nlgeom
            else "*FREQUENCY"
            if step.frequency is not None
            else "*DYNAMIC"
            if step.dynamic is not None
            else "*MODAL DYNAMIC"
            if step.modal_dynamic is not None
            else None
        )
        if what is not None:
            raise NotImplementedError(
                f"{step.location}: {what} with C3D8I elements is not supported yet (their "
                "incompatible modes are condensed for small-strain static steps only)"
            )


def build_model(
    deck: Deck, comm: MPI.Comm = MPI.COMM_WORLD, *, area_weights: str = "ccx"
) -> CalculixModel:
    """Build the dolfinx model of a parsed CalculiX deck (collective).

    Args:
        deck: The deck (``read_deck``).
        comm: Communicator. On several processes the mesh is distributed by dolfinx from rank
            0's cells (docs/method.md §14.5); every process must have read the same deck.
        area_weights: Spring areas of 2D decks, ``"ccx"`` (default: the shares of ccx's expanded
            faces) or ``"consistent"`` (``ContactPair.area_weights``, docs/method.md §23.3).

    Returns:
        The :class:`CalculixModel` (its ``deck`` has the slave nodes ADJUST of ``*TIE`` moved).

    Raises:
        ValueError: mixed element types, faces that are not boundary facets, bad material data.
        NotImplementedError: features not supported yet,
            naming the keyword and ``file:line``. Raised on every process.
    """
    deck, mixed = mixed_hexahedra(deck)  # C3D8 beside C3D20(R): 20-node cells (§27)
    if mixed is not None:
        check_mixed_deck(deck)
    block = element_block(deck)
    etype = block.type
    if etype.name == "C3D15":
        check_c3d15_deck(deck, block)
    models = element_models(deck, block)
    if len(deck.elements) > 1:  # ccx's quasi-axisymmetric mix, one block (docs/method.md §26)
        deck = dataclasses.replace(deck, elements={etype.name: block})
    thickness = np.ones(block.ids.size)
    if etype.tdim == 2:  # ccx's 2D elements, natively in 2D (docs/method.md §23)
        if deck.transformed_nodes.size:
            raise NotImplementedError(
                f"{deck.path}: *TRANSFORM with {etype.name} elements is not supported yet "
                "(docs/method.md §28)"
            )
        check_two_d_deck(deck, block, models)
        thickness = section_thickness(deck, block, models)
    # *TIE: ADJUST moves slave nodes before the mesh is made (docs/method.md §19)
    meshed = np.isin(deck.node_ids, block.connectivity)
    deck, tie_blocks = tie_constraints(deck, meshed, warn=comm.rank == 0)
    carried = collectives.collectively(comm, carried_nodes, deck, block)  # in no element (§29.6)
    mesh = create_mesh(deck, block, comm, carried)
    V = compat.vector_space(mesh, "Lagrange", etype.degree)
    u = dolfinx.fem.Function(V, name="displacement")
    node_dof, dof_node, node_vertex, original = numbering(deck, mesh, V)
    element_cell = np.full(block.ids.size, -1, dtype=np.int64)
    element = original < block.ids.size  # the others are carrier cells
    element_cell[original[element]] = np.flatnonzero(element)
    cell_element = np.full(original.size, -1, dtype=np.int64)
    cell_element[element] = block.ids[original[element]]
    held = carrier_dofs(mesh, V, deck, carried)

    maps = mesh_maps(deck, block, mesh, node_vertex, node_dof, element_cell, carried)
    error = None
    try:  # local work: a bad face found by one process is an error on all (no collective inside)
        surfaces, surface_tags, surface_faces = deck_surfaces(deck, mesh, maps)
        pairs = contact_pairs(
            deck, surfaces, maps, thickness=thickness, models=models, area_weights=area_weights
        )
        steps, amplitude_names, pressure_tags, num_groups = schedules(deck, maps, mesh)
        springs_follow = check_springs(deck, maps.meshed)
        if etype.name == "C3D8I":
            check_incompatible_modes(deck)
        check_plastic_deck(deck, etype)
    except (ValueError, NotImplementedError) as exc:
        error = exc
    validation.raise_collectively(comm, error)
    mu, lmbda = lame(deck, block, mesh, element_cell)

    kinds = {step.nlgeom for step in deck.steps}
    nlgeom = dolfinx.fem.Constant(mesh, 0.0) if len(kinds) > 1 else None
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": etype.quadrature_degree})
    linear_cells = np.zeros(0, np.int64)
    mass_dx = dx if etype.name == "C3D8" else ufl.dx(domain=mesh)  # ccx's C3D8 mass (§27.4)
    if etype.name == "C3D15":  # ccx's 9 points (docs/method.md §34)
        dx = mass_dx = ufl.Measure("dx", domain=mesh, metadata=c3d15_metadata())
    if mixed is not None:
        linear_cells = element_cell[mixed.linear & (element_cell >= 0)]
        cells = element_cell[element_cell >= 0]
        mass_dx = _mixed_measure(mesh, cells, linear_cells, None)
        if etype.name == "C3D20":  # C3D8's 2x2x2 beside C3D20's 3x3x3 Gauss points
            dx = _mixed_measure(mesh, cells, linear_cells, 5)
    rules = None
    if deck.wedges.size and mixed is None:  # every process read the deck
        rules = wedge_rules(mesh, comm)  # ccx's C3D6 rule on the wedges (docs/method.md §30.5)
        if rules.classes:
            wedge_tags = rules.tags(mesh)
            _, dx = rules.measures(mesh, wedge_tags, etype.quadrature_degree)
            mass_dx = dx
        else:
            rules = None
    thermal = None
    if collectives.collectively(comm, is_thermal, deck):
        if etype.tdim == 2:
            raise NotImplementedError(
                f"{deck.path}: coupled temperature-displacement steps with {etype.name} elements "
                "are not supported yet"
            )
        thermal = thermal_model(deck, block, mesh, etype.degree, node_dof, element_cell, dx)
    v = ufl.TestFunction(V)
    printed_force = None
    sections = None
    nlgeom_2d = etype.tdim == 2 and True in kinds
    if etype.tdim == 2 and (nlgeom_2d or len(set(models)) > 1 or np.ptp(thickness) > 0.0):
        sections = plane_sections(mesh, models, thickness, element_cell)
    if sections is not None:  # per-cell models, NLGEOM (docs/method.md §26)
        weight = sections.weight()
        if nlgeom_2d:
            F = sections.deformation_gradient(u, mu, lmbda)
            E = 0.5 * (F.T * F - ufl.Identity(3))
            P = F * (2 * mu * E + lmbda * ufl.tr(E) * ufl.Identity(3))
            sigma = P * F.T / ufl.det(F)
        else:
            H = sections.grad(u, mu, lmbda)
            sigma = 2 * mu * ufl.sym(H) + lmbda * ufl.tr(H) * ufl.Identity(3)
            P = sigma
        internal_force = ufl.inner(P, sections.grad(v)) * weight * dx
        if "axisymmetric" in set(models):  # ccx's RF: without the hoop term (§23)
            printed_force = ufl.inner(P, plane_kinematics(v, "plane strain")) * weight * dx
    elif etype.tdim == 2:  # small strain; the 3x3 stress of the 2D model, weighted (§23)
        weight = volume_weight(mesh, etype.model, float(thickness[0]) if thickness.size else 1.0)
        H = plane_kinematics(u, etype.model, plane_stress_factor(mu, lmbda))
        sigma = 2 * mu * ufl.sym(H) + lmbda * ufl.tr(H) * ufl.Identity(3)
        P = sigma
        internal_force = ufl.inner(sigma, plane_kinematics(v, etype.model)) * weight * dx
        if etype.model == "axisymmetric":  # ccx's RF: without the hoop term (§23)
            printed_force = ufl.inner(sigma, plane_kinematics(v, "plane strain")) * weight * dx
    else:
        kinematics = nlgeom if nlgeom is not None else float(True in kinds)
        F, P, sigma = stresses(
            u, mu, lmbda, kinematics, None if thermal is None else thermal.thermal_strain()
        )
        internal_force = ufl.inner(P, ufl.grad(v)) * dx
    laws: list[J2Plasticity | FiniteStrainJ2Plasticity] = []
    if etype.tdim == 3:  # *PLASTIC sections: their own law, the elastic form elsewhere (§21.6)
        laws, tags = plastic_laws(
            deck,
            block,
            u,
            element_cell,
            etype.quadrature_degree,
            finite=True in kinds,
            elastic_values=None if rules is None else rules.values,
            wedge_classes=None if rules is None else rules.classes_of_cells,
            rule_classes=() if rules is None else rules.classes,
        )
    if laws and rules is not None:  # the elastic wedges' rule beside the laws' cells
        dx_elastic, dx = rules.measures(
            mesh, tags, etype.quadrature_degree, [law.dx for law in laws]
        )
        mass_dx = dx
        internal_force = ufl.inner(P, ufl.grad(v)) * dx_elastic
    elif laws:
        dx_elastic = ufl.Measure(
            "dx",
            domain=mesh,
            subdomain_data=tags,
            metadata={"quadrature_degree": etype.quadrature_degree},
        )(0)
        internal_force = ufl.inner(P, ufl.grad(v)) * dx_elastic
    elif rules is not None:
        internal_force = ufl.inner(P, ufl.grad(v)) * dx
    residual = internal_force
    pressures = [dolfinx.fem.Constant(mesh, 0.0) for _ in range(num_groups)]
    pressure_loads = None
    follower = None
    if isinstance(pressure_tags, C3D15Pressures):  # C3D15: no ds on prisms (§34.4)
        if True in kinds:  # NLGEOM (every step, check_c3d15_deck): on the current faces
            follower = _follower_pressure(deck, pressure_tags, block, V, node_dof, pressures)
        else:  # forces per group on the reference faces
            pressure_loads = _held_columns(pressure_tags.unit_forces(deck, block), node_dof)
        pressure_tags = None
    elif pressures:
        ds = ufl.Measure(
            "ds",
            domain=mesh,
            subdomain_data=pressure_tags,
            metadata={"quadrature_degree": etype.face_quadrature_degree},
        )
        N = ufl.FacetNormal(mesh)
        if nlgeom_2d:  # follower: the current ring or layer area J F^-T N (§26)
            t3 = ufl.det(F) * ufl.inv(F).T * ufl.as_vector([N[0], N[1], 0])
            traction_map = weight * ufl.as_vector([t3[0], t3[1]])
        elif etype.tdim == 2:  # small strain, per thickness or ring
            traction_map = weight * N
        else:
            traction_map = ufl.det(F) * ufl.inv(F).T * N  # J F^-T N; N itself when nlgeom = 0
        for g, p in enumerate(pressures):
            residual += p * ufl.inner(traction_map, v) * ds(g + 1)
    gravity = None
    if any(step.gravity for step in deck.steps):
        gravity, body_force = _gravity(deck, block, mesh, element_cell)
        residual -= ufl.inner(body_force, v) * dx
    jacobian = None
    if laws:  # the plastic terms' consistent tangent (ufl.derivative cannot see through them)
        du = ufl.TrialFunction(V)
        jacobian = ufl.derivative(residual, u, du)
        for law in laws:
            jacobian += law.jacobian(du, v)
            residual += law.residual(v)
            internal_force += law.residual(v)
    nodal_loads = dolfinx.fem.Function(V, name="nodal_loads")
    constraints, reference_terms, free_references = equation_constraints(deck, maps.meshed)
    # terms on ccx node numbers, held by any process: global dofs (docs/method.md §14.9)
    constraints = global_constraints(V, constraints, node_ids=dof_node)
    if etype.num_nodes == 20:
        constraints += serendipity_constraints(V)  # C3D20's space (docs/method.md §13.5)
    if mixed is not None:  # C3D8 cells: trilinear (§27)
        constraints.append(trilinear_constraints(V, linear_cells))
    if etype.tdim == 2 and etype.num_nodes == 8:
        constraints += quad_serendipity_constraints(V)  # CPE8's space (§23)
    if etype.name == "C3D15":
        constraints += wedge_serendipity_constraints(V)  # C3D15's space (§34)
    for tie in tie_blocks:  # every process read them: rank 0 gives them
        rows = slice(None) if comm.rank == 0 else slice(0)
        given = LinearConstraintBlock(
            tie.nodes[rows], tie.components[rows], tie.coefficients[rows], tie.values[rows],
            name=tie.name, drop_prescribed=tie.drop_prescribed,
        )  # fmt: skip
        constraints.append(global_constraint_block(V, given, node_ids=dof_node))

    springs = deck_springs(deck, V, node_dof, bool(springs_follow)) if deck.springs else []
    modes = None
    if etype.name == "C3D8I":  # ccx 2.20's modes: unscaled (measured, docs/method.md §22)
        modes = IncompatibleModes(V, mu, lmbda, taylor=False)
    bc_spaces = []
    gdim = mesh.geometry.dim
    num_unrolled = gdim * (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts)
    for component in range(gdim):
        Vi, dof_map = compat.component_space(V, component)
        inverse = np.full(num_unrolled, -1, dtype=np.int64)
        inverse[np.asarray(dof_map)] = np.arange(len(dof_map))
        bc_spaces.append((Vi, inverse, dolfinx.fem.Function(Vi)))

    return CalculixModel(
        deck=deck,
        element_type=etype,
        mesh=mesh,
        V=V,
        u=u,
        node_dof=node_dof,
        dof_node=dof_node,
        node_vertex=node_vertex,
        element_cell=element_cell,
        cell_element=cell_element,
        surfaces=surfaces,
        surface_tags=surface_tags,
        surface_faces=surface_faces,
        pairs=pairs,
        mu=mu,
        lmbda=lmbda,
        nlgeom=nlgeom,
        dx=dx,
        first_piola=P,
        cauchy=sigma,
        residual=residual,
        nodal_loads=nodal_loads,
        pressures=pressures,
        pressure_tags=pressure_tags,
        steps=steps,
        amplitude_names=amplitude_names,
        _bc_spaces=bc_spaces,
        constraints=constraints,
        carrier_dofs=held,
        reference_terms=reference_terms,
        free_references=free_references,
        springs=springs,
        internal_force=internal_force,
        printed_force=printed_force,
        printed_scale=printed_scale(
            "axisymmetric" if "axisymmetric" in set(models) else etype.model,
            etype.num_nodes > etype.num_corners,
        ),
        thermal=thermal,
        incompatible_modes=modes,
        plasticity=laws,
        jacobian=jacobian,
        axisymmetric_elements=block.ids[models == "axisymmetric"] if etype.tdim == 2 else None,
        sections=sections,
        spring_only_nodes=_node_slaves(deck) if etype.tdim == 2 else None,
        gravity=gravity,
        pressure_loads=pressure_loads,
        follower_pressure=follower,
        mass_dx=mass_dx,
    )


def _node_slaves(deck: Deck) -> np.ndarray | None:
    """``(k, 2)`` node and component (0-based) of the free components of node-based slaves.

    The components of the deck's node-based slave surfaces without a ``*BOUNDARY`` in any step
    (ccx prints the reaction at a prescribed one); None without any.
    """
    names = {pair.slave for pair in deck.contact_pairs}
    nodes = [deck.surfaces[n].nodes for n in names if deck.surfaces[n].type == "NODE"]
    if not nodes:
        return None
    ids = np.unique(np.concatenate(nodes))
    free = np.ones((ids.size, 2), dtype=bool)
    for card in [*deck.boundaries, *(b for step in deck.steps for b in step.boundaries)]:
        held = np.isin(ids, card.nodes)
        for dof in range(card.first_dof, min(card.last_dof, 2) + 1):
            free[held, dof - 1] = False
    node, component = np.nonzero(free)
    return np.column_stack([ids[node], component])


def _mixed_measure(
    mesh: dolfinx.mesh.Mesh, cells: np.ndarray, linear_cells: np.ndarray, degree: int | None
) -> CellMeasures:
    """``dx`` with 2x2x2 Gauss points on the C3D8 cells, ``degree`` on the others."""
    values = np.full(cells.size, 2, dtype=np.int32)
    values[np.isin(cells, linear_cells)] = 1
    order = np.argsort(cells)
    tags = dolfinx.mesh.meshtags(
        mesh, mesh.topology.dim, cells[order].astype(np.int32), values[order]
    )
    return CellMeasures(mesh, tags, {1: 2, 2: degree})


def _gravity(
    deck: Deck, block, mesh: dolfinx.mesh.Mesh, element_cell: np.ndarray
) -> tuple[dolfinx.fem.Function, ufl.core.expr.Expr]:
    """The cellwise ``GRAV`` acceleration and the body force ``rho g`` (docs/method.md §27).

    Every element a ``GRAV`` line loads needs a ``*DENSITY`` (an error naming the line).
    """
    if block.type.tdim == 2:
        line = next(g for step in deck.steps for g in step.gravity)
        raise not_supported(f"*DLOAD, GRAV with {block.type.name} elements", line.location)
    rho, given = density(deck, block, mesh, element_cell)
    order = np.argsort(block.ids)
    for step in deck.steps:
        for line in step.gravity:
            rows = order[np.searchsorted(block.ids, line.elements, sorter=order)]
            if not np.all(given[rows]):
                element = int(line.elements[np.argmax(~given[rows])])
                raise ValueError(
                    f"{line.location}: *DLOAD, GRAV on element {element}, whose material has "
                    "no *DENSITY"
                )
    acceleration = dolfinx.fem.Function(compat.vector_space(mesh, "DG", 0), name="gravity")
    return acceleration, rho * acceleration


def _held_columns(unit: np.ndarray, node_dof: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The unrolled dofs this process holds and their columns of deck-wide ``(groups, 3N)``."""
    keys = np.flatnonzero(np.repeat(node_dof >= 0, 3) & np.any(unit != 0.0, axis=0))
    dofs = 3 * node_dof[keys // 3] + keys % 3
    return dofs, np.ascontiguousarray(unit[:, keys])


def _follower_pressure(
    deck: Deck,
    loaded: C3D15Pressures,
    block: ElementBlock,
    V: dolfinx.fem.FunctionSpace,
    node_dof: np.ndarray,
    pressures: list[dolfinx.fem.Constant],
) -> FollowerPressure:
    """The C3D15 pressures of an NLGEOM deck on the current faces (collective)."""
    index_map = V.dofmap.index_map
    held = node_dof >= 0
    global_node = np.full(node_dof.size, -1, dtype=np.int64)
    global_node[held] = index_map.local_to_global(node_dof[held].astype(np.int32))
    V.mesh.comm.Allreduce(MPI.IN_PLACE, global_node, op=MPI.MAX)
    faces = [
        PressureFaces(face_type, global_node[nodes], deck.node_coords[nodes], group, rule)
        for face_type, nodes, group, rule in loaded.faces(deck, block)
    ]
    return FollowerPressure(V, faces, pressures)
