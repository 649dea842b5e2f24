"""A parsed CalculiX deck as dolfinx objects: mesh, UFL residual, loads per step and contact pairs.

``build_model`` turns a :class:`~dolfinx_ntf.calculix.deck.Deck` into a :class:`CalculixModel`:

    - the mesh of the deck's one element type (C3D4 -> P1 tetrahedra, C3D8 -> Q1 hexahedra,
      C3D10 -> P2 tetrahedra with P2 geometry, C3D20/C3D20R -> Q2 hexahedra constrained to the
      serendipity space, docs/method.md §13.5) and the maps between ccx node/element numbers and
      dolfinx block dofs/cells (always through per-cell tables, never by assuming equal numbers);
    - surfaces: element-face surfaces as facet tags (one ``MeshTags`` per ccx surface, value 1)
      wrapped in :class:`~dolfinx_ntf.FacetSurface`, ``TYPE=NODE`` surfaces as
      :class:`~dolfinx_ntf.NodeSurface`;
    - the bulk residual: small-strain isotropic elasticity, or total-Lagrangian St.Venant-Kirchhoff
      with ``NLGEOM`` (switched by a Constant when a deck has both kinds of steps), integrated like
      ccx (C3D8 2x2x2 Gauss, C3D4 one point, C3D10 four points, C3D20 3x3x3, C3D20R 2x2x2);
      ``*DLOAD`` pressures on the
      reference faces, or as follower loads ``p J F^-T N`` with ``NLGEOM``;
    - the loads and prescribed displacements of every step with ccx's rules (:class:`StepLoads`);
    - the contact pairs with their pressure-overclosure laws.

Load rules (ccx manual, ``*AMPLITUDE``, ``*BOUNDARY``, ``*CLOAD``, ``*DLOAD``, ``*STATIC``):
    - Without an amplitude a static step ramps every load linearly from its value at the end of the
      previous step (0 at the start) to its reference value; with an amplitude the value is the
      reference times the amplitude at the step time (or total time with ``TIME=TOTAL TIME``).
    - At the end of a step, references with a step-time amplitude become their actual values and the
      amplitude is dropped; total-time amplitudes stay.
    - ``OP=NEW`` on the first card of a kind in a step removes all earlier ones (loads then ramp
      down to 0, prescribed displacements are released). Within a step, repeated
      ``*CLOAD``/``*DLOAD`` values on the same dof or face add up and repeated ``*BOUNDARY`` values
      replace; the amplitude of the last card applies.
    - A prescribed displacement ramps from the displacement at the start of the step.
    - Model-definition ``*BOUNDARY`` cards act as if given at the start of step 1.

On several processes (docs/method.md §14.5) every process reads the whole deck; the mesh is
distributed by dolfinx from rank 0's cells, and the numbering maps hold this process's nodes and
cells only (-1 elsewhere); ``*EQUATION`` terms are numbered globally (docs/method.md §14.9).
"""

from __future__ import annotations

import logging
import typing
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

import dolfinx.cpp.mesh
import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.problem import ContactPair, ContactProblem
from dolfinx_ntf.fem.constraints import (
    LinearConstraint,
    LinearConstraintBlock,
    num_equations,
)
from dolfinx_ntf.fem.serendipity import add_centres, serendipity_constraints
from dolfinx_ntf.fem.surfaces import FacetSurface, NodeSurface
from dolfinx_ntf.kernels.laws import (
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    SurfaceInteraction,
    TabularLaw,
)
from dolfinx_ntf.parallel.global_constraints import global_constraints

from .deck import Deck, Step
from .elements import ELEMENT_TYPES, ElementType

__all__ = [
    "CELL_PERMUTATIONS",
    "INTEGRATION_POINTS",
    "CalculixModel",
    "StepLoads",
    "build_model",
]

#: dolfinx cell node order as 0-based indices into the ccx element's nodes, by ccx element type.
CELL_PERMUTATIONS: dict[str, np.ndarray] = {n: t.to_dolfinx for n, t in ELEMENT_TYPES.items()}

#: ccx integration points of each element type in ccx order (``*EL PRINT`` rows), as dolfinx
#: reference coordinates.
INTEGRATION_POINTS: dict[str, np.ndarray] = {
    n: t.integration_points for n, t in ELEMENT_TYPES.items()
}


# ----------------------------------------------------------------------------- load schedules


@dataclass(eq=False)
class _Schedule:
    """Load history of one step per key: ``ref A(t)`` with an amplitude, else a ramp to ``ref``."""

    start: np.ndarray
    ref: np.ndarray
    amplitude: np.ndarray  # amplitude index, -1 for none


@dataclass(eq=False)
class StepLoads:
    """Loads and prescribed displacements of one step, ready to be evaluated at any step time.

    Attributes:
        step: The deck step.
        total_time_start: Total time at the start of the step.
        cload_dofs: ``(K,)`` unrolled dofs of ``V`` carrying a concentrated force in this step.
        cload: Force history of those dofs.
        pressure: History of each pressure group's pressure (see ``CalculixModel.pressures``).
        bc_dofs: ``(B,)`` sorted unrolled dofs of ``V`` with a prescribed displacement.
        bc: Prescribed-value history; ``bc.start`` is filled by :meth:`CalculixModel.begin_step`.
        reference_keys: ``(R,)`` keys ``3 node row + component`` of the prescribed components of
            nodes in no element (reference nodes of ``*EQUATION``); ``reference`` their history,
            from their value at the end of the previous step; ``reference_force_keys`` and
            ``reference_force`` likewise for their ``*CLOAD`` forces.
    """

    step: Step
    total_time_start: float
    cload_dofs: np.ndarray
    cload: _Schedule
    pressure: _Schedule
    bc_dofs: np.ndarray
    bc: _Schedule
    reference_keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    reference: _Schedule | None = None
    reference_force_keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    reference_force: _Schedule | None = None

    @property
    def period(self) -> float:
        """Step time period."""
        return self.step.static.period


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
            for C3D20/C3D20R the serendipity constraints of the face and cell centres (§13.5).
        reference_terms: ``(constraint, keys, coefficients)`` of the ``*EQUATION`` terms on nodes
            in no element, whose prescribed values move to the constraint's right-hand side.
        free_references: Components of nodes in no element without ``*BOUNDARY``, eliminated.
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
    surfaces: dict[str, FacetSurface | NodeSurface]
    surface_tags: dict[str, compat.MeshTags]
    surface_faces: dict[str, tuple[np.ndarray, np.ndarray]]
    pairs: list[ContactPair]
    mu: dolfinx.fem.Function
    lmbda: dolfinx.fem.Function
    nlgeom: dolfinx.fem.Constant | None
    dx: ufl.Measure
    first_piola: typing.Any
    cauchy: typing.Any
    residual: typing.Any
    nodal_loads: dolfinx.fem.Function
    pressures: list[dolfinx.fem.Constant]
    pressure_tags: compat.MeshTags | None
    steps: list[StepLoads]
    amplitude_names: list[str]
    _bc_spaces: list = field(default_factory=list, repr=False)
    constraints: list[LinearConstraint | LinearConstraintBlock] = field(default_factory=list)
    reference_terms: list[tuple[int, np.ndarray, np.ndarray]] = field(default_factory=list)
    free_references: list[FreeReference] = field(default_factory=list)

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
            dofs = loads.bc_dofs[loads.bc_dofs % 3 == component].astype(np.int32)
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
        for constant, value in zip(
            self.pressures, self._evaluate(loads.pressure, fraction, step_time, total)
        ):
            constant.value = value
        values = self._evaluate(loads.bc, fraction, step_time, total)
        for component, (_, inverse, g) in enumerate(self._bc_spaces):
            mask = loads.bc_dofs % 3 == component
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
        self, schedule: _Schedule, fraction: float, step_time: float, total_time: float
    ) -> np.ndarray:
        value = schedule.start + (schedule.ref - schedule.start) * fraction
        for index in np.unique(schedule.amplitude[schedule.amplitude >= 0]):
            amp = self.deck.amplitudes[self.amplitude_names[index]]
            t = total_time if amp.total_time else step_time
            mask = schedule.amplitude == index
            value[mask] = schedule.ref[mask] * np.interp(t, amp.times, amp.values)
        return value

    # -- problem -----------------------------------------------------------------------------------

    def create_problem(
        self, bcs: typing.Sequence[compat.DirichletBC] = (), **options
    ) -> ContactProblem:
        """The :class:`~dolfinx_ntf.ContactProblem` of the deck (bulk only without contact pairs).

        Args:
            bcs: Initial Dirichlet conditions (usually ``begin_step(0)``).
            options: :class:`~dolfinx_ntf.ContactProblem` options (``symmetric``, ``jit_options``).
        """
        options.setdefault("constraints", self.constraints)
        problem = ContactProblem(self.residual, self.u, self.pairs, bcs, **options)
        problem.nodal_loads = self.nodal_loads
        return problem


# ----------------------------------------------------------------------------- building


def _not_supported(what: str, location) -> NotImplementedError:
    return NotImplementedError(f"{location}: {what} is not supported yet")


def _check_supported(deck: Deck) -> None:
    """Deck features the solver cannot run yet: a clear error naming the keyword and line."""


def _element_block(deck: Deck):
    blocks = [b for b in deck.elements.values() if b.ids.size]
    if not blocks:
        raise ValueError(f"{deck.path}: the deck has no elements")
    if len(blocks) > 1:
        names = ", ".join(f"{b.type.name} (first at {b.locations[0]})" for b in blocks)
        raise ValueError(
            f"{deck.path}: the mesh mixes element types {names}; use one element type per deck"
        )
    return blocks[0]


def _create_mesh(deck: Deck, block, comm: MPI.Comm) -> dolfinx.mesh.Mesh:
    domain = compat.coordinate_element(block.type.cell, block.type.degree)
    serendipity = block.type.num_nodes == 20  # C3D20(R): 27-node cells (docs/method.md §13.5)
    if comm.rank == 0:
        cells = deck.node_index(block.connectivity)[:, block.type.to_dolfinx]
        x = np.asarray(deck.node_coords, dtype=np.float64)
        if serendipity:
            cells, x = add_centres(cells, x)
    else:
        cells = np.zeros((0, 27 if serendipity else block.type.num_nodes), dtype=np.int64)
        x = np.zeros((0, 3))
    return compat.create_mesh(comm, cells.astype(np.int64), x, domain)


def _numbering(deck: Deck, mesh: dolfinx.mesh.Mesh, V: dolfinx.fem.FunctionSpace):
    """node_dof, dof_node, node_vertex, element_cell, cell_element through per-cell tables."""
    tdim = mesh.topology.dim
    num_cells = mesh.topology.index_map(tdim).size_local + mesh.topology.index_map(tdim).num_ghosts
    geometry_dofs = compat.geometry_dofs(mesh)[:num_cells]
    space_dofs = compat.cell_dofs(V)[:num_cells]
    if geometry_dofs.shape != space_dofs.shape:
        raise RuntimeError("the displacement space and the geometry have different cell layouts")
    num_geometry = mesh.geometry.x.shape[0]
    dof_of_geometry = np.full(num_geometry, -1, dtype=np.int64)
    dof_of_geometry[geometry_dofs.ravel()] = space_dofs.ravel()
    input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    deck_node = input_index < deck.node_ids.size  # not C3D20's added face and cell centres
    node_dof = np.full(deck.node_ids.size, -1, dtype=np.int64)
    node_dof[input_index[deck_node]] = dof_of_geometry[deck_node]
    num_dofs = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    dof_node = np.full(num_dofs, -1, dtype=np.int64)  # -1: an added centre, no ccx node
    dof_node[dof_of_geometry[deck_node]] = deck.node_ids[input_index[deck_node]]

    num_vertices = mesh.topology.index_map(0).size_local + mesh.topology.index_map(0).num_ghosts
    vertices = np.arange(num_vertices, dtype=np.int32)
    vertex_geometry = compat.entities_to_geometry(mesh, 0, vertices).ravel()
    node_vertex = np.full(deck.node_ids.size, -1, dtype=np.int64)
    node_vertex[input_index[vertex_geometry]] = vertices

    original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:num_cells]
    return node_dof, dof_node, node_vertex, original


def _facet_finder(mesh: dolfinx.mesh.Mesh):
    """A function mapping ``(F, k)`` facet corner vertices to local facet indices (-1 if none)."""
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, 0)
    mesh.topology.create_connectivity(tdim - 1, tdim)
    f_to_v = mesh.topology.connectivity(tdim - 1, 0)
    num_facets = (
        mesh.topology.index_map(tdim - 1).size_local + mesh.topology.index_map(tdim - 1).num_ghosts
    )
    width = f_to_v.offsets[1] - f_to_v.offsets[0] if num_facets else 3
    keys = np.sort(f_to_v.array.reshape(num_facets, width).astype(np.int64), axis=1)
    order = np.lexsort(keys.T[::-1])
    sorted_keys = keys[order]

    def find(corners: np.ndarray) -> np.ndarray:
        query = np.sort(np.asarray(corners, dtype=np.int64), axis=1)
        if query.shape[1] != width:
            raise ValueError(f"faces with {query.shape[1]} corners, mesh facets have {width}")
        lo, hi = (
            np.zeros(query.shape[0], dtype=np.int64),
            np.full(query.shape[0], num_facets, dtype=np.int64),
        )
        # vectorized lexicographic binary search over the sorted facet keys
        for _ in range(int(np.ceil(np.log2(num_facets + 1))) + 1):
            mid = (lo + hi) // 2
            active = lo < hi
            cand = sorted_keys[np.minimum(mid, num_facets - 1)]
            diff = cand - query
            first = np.argmax(diff != 0, axis=1)
            sign = diff[np.arange(query.shape[0]), first]
            less = active & (sign < 0)
            lo = np.where(less, mid + 1, lo)
            hi = np.where(active & ~less, mid, hi)
        pos = np.minimum(lo, num_facets - 1)
        found = np.all(sorted_keys[pos] == query, axis=1) & (query.min(axis=1) >= 0)
        return np.where(found, order[pos], -1)

    return find


def _exterior(mesh: dolfinx.mesh.Mesh, facets: np.ndarray) -> np.ndarray:
    tdim = mesh.topology.dim
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    return (f_to_c.offsets[facets + 1] - f_to_c.offsets[facets]) == 1


def _element_faces_to_facets(
    deck: Deck, model_parts: dict, element_ids: np.ndarray, faces: np.ndarray, what: str, location
) -> tuple[np.ndarray, np.ndarray]:
    """Local facets and ccx face nodes ``(F, n)`` of element faces (1-based face numbers).

    The facet is -1 for faces of elements this process does not hold.
    """
    block, node_vertex, find = model_parts["block"], model_parts["node_vertex"], model_parts["find"]
    etype = block.type
    order = np.argsort(block.ids)
    pos = np.minimum(np.searchsorted(block.ids, element_ids, sorter=order), block.ids.size - 1)
    rows = order[pos]
    nodes = block.connectivity[rows[:, None], etype.faces[faces - 1]]
    corners = node_vertex[deck.node_index(nodes[:, : etype.face_corners])]
    here = model_parts["element_cell"][rows] >= 0
    facets = np.full(here.size, -1, dtype=np.int64)
    if np.any(here):  # a process without cells has no facets to search
        facets[here] = find(corners[here])
    if np.any(here & (facets < 0)):
        bad = int(np.argmax(here & (facets < 0)))
        raise ValueError(
            f"{location}: {what}: face S{faces[bad]} of element {element_ids[bad]} is not a "
            "facet of "
            "the mesh"
        )
    return facets, nodes


def _surfaces(deck: Deck, mesh, parts: dict):
    surfaces: dict[str, FacetSurface | NodeSurface] = {}
    tags: dict[str, compat.MeshTags] = {}
    faces: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    node_vertex, corner = parts["node_vertex"], parts["corner"]
    for name, surface in deck.surfaces.items():
        if surface.type == "NODE":
            rows = deck.node_index(surface.nodes)
            if not np.all(parts["meshed"][rows]):
                node = int(surface.nodes[np.argmax(~parts["meshed"][rows])])
                raise ValueError(
                    f"{surface.location}: *SURFACE {name}, TYPE=NODE: node {node} belongs to no "
                    "element"
                )
            vertices, dofs = node_vertex[rows], parts["node_dof"][rows]
            midside = np.unique(dofs[~corner[rows] & (dofs >= 0)]).astype(np.int32)  # quadratic
            if not np.all(corner[rows]) and parts["block"].type.num_nodes != 20:  # C3D20 only
                node = int(surface.nodes[np.argmax(~corner[rows])])
                raise _not_supported(
                    f"*SURFACE {name}, TYPE=NODE with node {node}, which is not an element "
                    f"corner, on {parts['block'].type.name} elements (midside nodes of "
                    "node-based surfaces: C3D20 only)",
                    surface.location,
                )
            vertices = np.unique(vertices[vertices >= 0]).astype(np.int32)  # this process's
            surfaces[name] = NodeSurface(vertices, name, midside_nodes=midside)
            continue
        facets, nodes = _element_faces_to_facets(
            deck, parts, surface.elements, surface.faces, f"*SURFACE {name}", surface.location
        )
        facets, first = np.unique(facets, return_index=True)
        if facets.size and facets[0] < 0:  # faces of other processes' elements
            facets, first = facets[1:], first[1:]
        inner = ~_exterior(mesh, facets)
        if np.any(inner):
            k = int(np.argmax(inner))
            raise ValueError(
                f"{surface.location}: *SURFACE {name}: face S{surface.faces[first[k]]} of element "
                f"{surface.elements[first[k]]} lies between two elements, not on the boundary"
            )
        tag = dolfinx.mesh.meshtags(
            mesh,
            mesh.topology.dim - 1,
            facets.astype(np.int32),
            np.ones(facets.size, dtype=np.int32),
        )
        tag.name = name
        tags[name] = tag
        faces[name] = (facets, nodes[first])
        surfaces[name] = FacetSurface(tag, 1)
    return surfaces, tags, faces


def _law(deck: Deck, interaction_name: str) -> PressureOverclosureLaw:
    behavior = deck.interactions[interaction_name].behavior
    kind = behavior.pressure_overclosure
    if kind == "EXPONENTIAL":
        c0, p0 = behavior.values
        return ExponentialLaw(c0=c0, p0=p0)
    if kind in ("LINEAR", "HARD"):
        elastic = next((m.elastic for m in deck.materials.values() if m.elastic is not None), None)
        if elastic is None:
            raise ValueError(
                f"{behavior.location}: {kind} contact needs an *ELASTIC material for its defaults"
            )
        values = tuple(behavior.values) + (None,) * (3 - len(behavior.values))
        return LinearLaw.with_ccx_defaults(elastic[0], *values[:3])
    if kind == "TABULAR":
        table = behavior.table
        if table.shape[1] != 2:
            raise _not_supported(
                "temperature-dependent *SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=TABULAR",
                behavior.location,
            )
        return TabularLaw(pressures=table[:, 0], overclosures=table[:, 1])
    raise _not_supported(f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE={kind}", behavior.location)


def _first_youngs_modulus(deck: Deck, location) -> float:
    """E of the first ``*ELASTIC`` material: ccx's reference for contact defaults."""
    elastic = next((m.elastic for m in deck.materials.values() if m.elastic is not None), None)
    if elastic is None:
        raise ValueError(f"{location}: contact defaults need an *ELASTIC material")
    return elastic[0]


def friction_of(deck: Deck, data) -> Friction:
    """A ``*FRICTION`` data line as ccx reads it: a missing or non-positive lambda is ``E/2``.

    The default is announced with a warning, as ccx does (docs/method.md §11.5).
    """
    e = _first_youngs_modulus(deck, data.location)
    if data.stick_slope is None or data.stick_slope <= 0.0:
        logging.getLogger("dolfinx_ntf").warning(
            " *WARNING in frictions: stick slope (lambda) missing or not positive at %s; "
            "using E/2 = %g",
            data.location,
            0.5 * e,
        )
        return Friction(data.mu, 0.5 * e)
    return Friction(data.mu, data.stick_slope)


def _adjust(deck: Deck, pair, parts: dict) -> float | NodeSurface | None:
    """The ADJUST of a pair: a distance, the vertices of a node set, or None."""
    if pair.adjust is None or isinstance(pair.adjust, float):
        return pair.adjust
    ids = deck.nsets[pair.adjust]
    vertices = parts["node_vertex"][deck.node_index(ids)]
    corner = parts["corner"][deck.node_index(ids)]
    if not np.all(corner):
        node = int(ids[np.argmax(~corner)])
        raise _not_supported(
            f"ADJUST={pair.adjust} with node {node}, which is not an element corner",
            pair.location,
        )
    return NodeSurface(np.unique(vertices[vertices >= 0]).astype(np.int32), pair.adjust)


def _contact_pairs(deck: Deck, surfaces: dict, parts: dict) -> list[ContactPair]:
    pairs = []
    for pair in deck.contact_pairs:
        law = _law(deck, pair.interaction)
        data = deck.interactions[pair.interaction].friction
        friction = None if data is None else friction_of(deck, data)
        pairs.append(
            ContactPair(
                surfaces[pair.slave],
                surfaces[pair.master],
                SurfaceInteraction(law, friction),
                small_sliding=pair.small_sliding,
                name=f"{pair.slave}-{pair.master}",
                adjust=_adjust(deck, pair, parts),
            )
        )
    return pairs


def _lame(deck: Deck, block, mesh, element_cell: np.ndarray):
    Q = compat.scalar_space(mesh, "DG", 0)
    mu, lmbda = dolfinx.fem.Function(Q, name="mu"), dolfinx.fem.Function(Q, name="lambda")
    for section in deck.sections:
        young, nu = deck.materials[section.material].elastic
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        order = np.argsort(block.ids)
        rows = order[np.searchsorted(block.ids, members, sorter=order)]
        cells = element_cell[rows]
        dofs = compat.cell_dofs(Q)[cells[cells >= 0], 0]
        mu.x.array[dofs] = young / (2 * (1 + nu))
        lmbda.x.array[dofs] = young * nu / ((1 + nu) * (1 - 2 * nu))
    return mu, lmbda


def _stresses(u, mu, lmbda, nlgeom):
    """First Piola-Kirchhoff and Cauchy stress; ``nlgeom`` 0 gives small-strain elasticity."""
    H = ufl.grad(u)
    Id = ufl.Identity(3)
    F = Id + nlgeom * H
    E = ufl.sym(H) + 0.5 * nlgeom * H.T * H
    S = 2 * mu * E + lmbda * ufl.tr(E) * Id
    P = F * S
    return F, P, P * F.T / ufl.det(F)


# -- schedules -------------------------------------------------------------------------------------


class _ScheduleBuilder:
    """ccx's reference-value bookkeeping of one load kind over the steps (module docstring)."""

    def __init__(self, size: int, amplitude_total: np.ndarray, add_within_step: bool) -> None:
        self.ref = np.zeros(size)
        self.amplitude = np.full(size, -1, dtype=np.int64)
        self.active = np.zeros(size, dtype=bool)
        self.end = np.zeros(size)
        self.amplitude_total = amplitude_total
        self.add = add_within_step
        self._touched = np.zeros(size, dtype=bool)

    def begin(self, new: bool) -> None:
        carried = self.amplitude >= 0
        step_time = carried & ~self.amplitude_total[np.maximum(self.amplitude, 0)]
        self.ref[step_time] = self.end[step_time]
        self.amplitude[step_time] = -1
        if new:
            self.ref[:] = 0.0
            self.amplitude[:] = -1
            self.active[:] = False
        self._touched[:] = False

    def card(self, keys: np.ndarray, value: float, amplitude: int) -> None:
        if self.add:
            fresh = keys[~self._touched[keys]]
            self.ref[fresh] = 0.0
            np.add.at(self.ref, keys, value)
        else:
            self.ref[keys] = value
        self._touched[keys] = True
        self.active[keys] = True
        self.amplitude[keys] = amplitude

    def finish(self, evaluate_end: typing.Callable[[_Schedule], np.ndarray]) -> _Schedule:
        schedule = _Schedule(self.end.copy(), self.ref.copy(), self.amplitude.copy())
        self.end = evaluate_end(schedule)
        return schedule


def _amplitude_index(deck: Deck, names: list[str], name: str | None) -> int:
    return -1 if name is None else names.index(name)


def _end_values(
    deck: Deck, names: list[str], schedule: _Schedule, period: float, total_end: float
) -> np.ndarray:
    value = schedule.ref.copy()
    for index in np.unique(schedule.amplitude[schedule.amplitude >= 0]):
        amp = deck.amplitudes[names[index]]
        mask = schedule.amplitude == index
        value[mask] = schedule.ref[mask] * np.interp(
            total_end if amp.total_time else period, amp.times, amp.values
        )
    return value


def _step_times(deck: Deck) -> list[float]:
    starts, total = [], 0.0
    for step in deck.steps:
        static = step.static
        if static.total_time_at_start is not None:
            total = static.total_time_at_start
        elif static.time_reset:
            total -= static.period
        starts.append(total)
        total += static.period
    return starts


def _schedules(deck: Deck, block, node_dof: np.ndarray, parts: dict, mesh):
    """Per-step schedules of forces, pressures (grouped) and prescribed displacements.

    Dofs are this process's; nodes in no element (``parts["meshed"]`` false) are references.
    """
    names = list(deck.amplitudes)
    amp_total = np.array([deck.amplitudes[n].total_time for n in names] + [False], dtype=bool)
    num_nodes = deck.node_ids.size
    cload = _ScheduleBuilder(3 * num_nodes, amp_total, add_within_step=True)
    dload = _ScheduleBuilder(6 * block.ids.size, amp_total, add_within_step=True)
    bound = _ScheduleBuilder(3 * num_nodes, amp_total, add_within_step=False)
    order = np.argsort(block.ids)
    starts = _step_times(deck)
    raw = []
    for s, step in enumerate(deck.steps):
        period = step.static.period
        total_end = starts[s] + period

        def end(schedule, period=period, total_end=total_end):
            return _end_values(deck, names, schedule, period, total_end)

        cards = (list(deck.boundaries) if s == 0 else []) + list(step.boundaries)
        bound.begin(new=bool(step.boundaries) and step.boundary_op == "NEW")
        for card in cards:
            keys = (
                3 * deck.node_index(card.nodes)[:, None]
                + np.arange(card.first_dof - 1, card.last_dof)
            ).ravel()
            bound.card(keys, card.value, _amplitude_index(deck, names, card.amplitude))
        bc = bound.finish(end)
        bc_active = bound.active.copy()

        cload.begin(new=step.cload_op == "NEW" and bool(step.cloads))
        for card in step.cloads:
            cload.card(
                3 * deck.node_index(card.nodes) + card.dof - 1,
                card.value,
                _amplitude_index(deck, names, card.amplitude),
            )
        forces = cload.finish(end)

        dload.begin(new=step.dload_op == "NEW" and bool(step.dloads))
        for card in step.dloads:
            rows = order[np.searchsorted(block.ids, card.elements, sorter=order)]
            dload.card(
                6 * rows + card.face - 1, card.value, _amplitude_index(deck, names, card.amplitude)
            )
        pressures = dload.finish(end)
        raw.append((bc, bc_active, forces, pressures))

    # Pressure groups: faces with the same history in every step share one Constant.
    used = np.zeros(6 * block.ids.size, dtype=bool)
    for _, _, _, p in raw:
        used |= (p.ref != 0) | (p.start != 0)
    keys = np.flatnonzero(used)
    history = (
        np.column_stack(
            [np.column_stack([p.start[keys], p.ref[keys], p.amplitude[keys]]) for _, _, _, p in raw]
        )
        if keys.size
        else np.zeros((0, 3 * len(raw)))
    )
    unique, group = np.unique(history, axis=0, return_inverse=True)
    group = group.ravel()
    pressure_tags = None
    if keys.size:
        facets, _ = _element_faces_to_facets(
            deck, parts, block.ids[keys // 6], keys % 6 + 1, "*DLOAD", deck.path
        )
        inner = facets >= 0  # a process without cells has no facet to look at
        inner[inner] = ~_exterior(mesh, facets[inner])
        if np.any(inner):
            k = int(np.argmax(inner))
            raise ValueError(
                f"{deck.path}: *DLOAD: face P{keys[k] % 6 + 1} of element "
                f"{block.ids[keys[k] // 6]} "
                "lies between two elements, not on the boundary"
            )
        facets, first = np.unique(facets, return_index=True)
        if facets.size and facets[0] < 0:  # faces of other processes' elements
            facets, first = facets[1:], first[1:]
        pressure_tags = dolfinx.mesh.meshtags(
            mesh,
            mesh.topology.dim - 1,
            facets.astype(np.int32),
            (group[first] + 1).astype(np.int32),
        )

    steps = []
    for s, (step, (bc, bc_active, forces, pressure)) in enumerate(zip(deck.steps, raw)):
        dofs3 = 3 * np.repeat(node_dof, 3) + np.tile(
            np.arange(3), num_nodes
        )  # unrolled dof of each key
        local = np.repeat(node_dof >= 0, 3)
        valid = np.repeat(parts["meshed"], 3)
        bc_keys = np.flatnonzero(bc_active & local)
        bc_dofs, first = np.unique(dofs3[bc_keys], return_index=True)
        bc_keys = bc_keys[first]
        loaded = (forces.ref != 0) | (forces.start != 0)
        f_keys = np.flatnonzero(loaded & local)
        columns = slice(3 * s, 3 * s + 3)
        group_history = unique[:, columns] if unique.size else np.zeros((0, 3))
        steps.append(
            StepLoads(
                step=step,
                total_time_start=starts[s],
                cload_dofs=dofs3[f_keys],
                cload=_Schedule(forces.start[f_keys], forces.ref[f_keys], forces.amplitude[f_keys]),
                pressure=_Schedule(
                    group_history[:, 0].copy(),
                    group_history[:, 1].copy(),
                    group_history[:, 2].astype(np.int64),
                ),
                bc_dofs=bc_dofs,
                bc=_Schedule(np.zeros(bc_dofs.size), bc.ref[bc_keys], bc.amplitude[bc_keys]),
                reference_force_keys=np.flatnonzero(loaded & ~valid),
                reference_force=_Schedule(
                    forces.start[loaded & ~valid],
                    forces.ref[loaded & ~valid],
                    forces.amplitude[loaded & ~valid],
                ),
                reference_keys=np.flatnonzero(bc_active & ~valid),
                reference=_Schedule(
                    bc.start[bc_active & ~valid],
                    bc.ref[bc_active & ~valid],
                    bc.amplitude[bc_active & ~valid],
                ),
            )
        )
    return steps, names, pressure_tags, int(unique.shape[0])


def build_model(deck: Deck, comm: MPI.Comm = MPI.COMM_WORLD) -> CalculixModel:
    """Build the dolfinx model of a parsed CalculiX deck (collective).

    Args:
        deck: The deck (``read_deck``).
        comm: Communicator. On several processes the mesh is distributed by dolfinx from rank
            0's cells (docs/method.md §14.5); every process must have read the same deck.

    Returns:
        The :class:`CalculixModel`.

    Raises:
        ValueError: mixed element types, faces that are not boundary facets, bad material data.
        NotImplementedError: features not supported yet,
            naming the keyword and ``file:line``. Raised on every process.
    """
    _check_supported(deck)
    block = _element_block(deck)
    etype = block.type
    mesh = _create_mesh(deck, block, comm)
    V = compat.vector_space(mesh, "Lagrange", etype.degree)
    u = dolfinx.fem.Function(V, name="displacement")
    node_dof, dof_node, node_vertex, original = _numbering(deck, mesh, V)
    element_cell = np.full(block.ids.size, -1, dtype=np.int64)
    element_cell[original] = np.arange(original.size)
    cell_element = block.ids[original]

    # over all processes (from the deck): nodes of an element, element corners
    meshed = np.zeros(deck.node_ids.size, dtype=bool)
    meshed[deck.node_index(block.connectivity)] = True
    corner = np.zeros(deck.node_ids.size, dtype=bool)
    corner[deck.node_index(block.connectivity[:, : etype.num_corners])] = True
    parts = {
        "block": block,
        "node_vertex": node_vertex,
        "node_dof": node_dof,
        "find": _facet_finder(mesh),
        "element_cell": element_cell,
        "meshed": meshed,
        "corner": corner,
    }
    error = None
    try:  # local work: a bad face found by one process is an error on all (no collective inside)
        surfaces, surface_tags, surface_faces = _surfaces(deck, mesh, parts)
        pairs = _contact_pairs(deck, surfaces, parts)
        steps, amplitude_names, pressure_tags, num_groups = _schedules(
            deck, block, node_dof, parts, mesh
        )
    except (ValueError, NotImplementedError) as exc:
        error = exc
    validation.raise_collectively(comm, error)
    mu, lmbda = _lame(deck, block, mesh, element_cell)

    kinds = {step.nlgeom for step in deck.steps}
    nlgeom = dolfinx.fem.Constant(mesh, 0.0) if len(kinds) > 1 else None
    F, P, sigma = _stresses(u, mu, lmbda, nlgeom if nlgeom is not None else float(True in kinds))
    v = ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": etype.quadrature_degree})
    residual = ufl.inner(P, ufl.grad(v)) * dx
    pressures = [dolfinx.fem.Constant(mesh, 0.0) for _ in range(num_groups)]
    if pressures:
        ds = ufl.Measure(
            "ds",
            domain=mesh,
            subdomain_data=pressure_tags,
            metadata={"quadrature_degree": etype.face_quadrature_degree},
        )
        N = ufl.FacetNormal(mesh)
        traction_map = ufl.det(F) * ufl.inv(F).T * N  # J F^-T N; N itself when nlgeom = 0
        for g, p in enumerate(pressures):
            residual += p * ufl.inner(traction_map, v) * ds(g + 1)
    nodal_loads = dolfinx.fem.Function(V, name="nodal_loads")
    constraints, reference_terms, free_references = _constraints(deck, meshed)
    # terms on ccx node numbers, held by any process: global dofs (docs/method.md §14.9)
    constraints = global_constraints(V, constraints, node_ids=dof_node)
    if etype.num_nodes == 20:
        constraints += serendipity_constraints(V)  # C3D20's space (docs/method.md §13.5)

    bc_spaces = []
    num_unrolled = 3 * (V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts)
    for component in range(3):
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
        reference_terms=reference_terms,
        free_references=free_references,
    )


@dataclass(frozen=True, eq=False)
class FreeReference:
    """A component of a node in no element, unknown and eliminated by one ``*EQUATION``.

    ``u_ref = sum(mesh_weights * u[mesh_dofs]) + sum(reference_weights * prescribed values of
    reference_keys)``; a force on it acts on ``mesh_dofs`` with ``mesh_weights`` (virtual work).

    Attributes:
        key: ``3 node row + component`` of the reference component.
        mesh_keys, mesh_weights: Keys ``3 node row + component`` of the mesh terms (nodes of
            elements, on any process) and their weights.
        reference_keys, reference_weights: Prescribed reference components and their weights.
    """

    key: int
    mesh_keys: np.ndarray
    mesh_weights: np.ndarray
    reference_keys: np.ndarray
    reference_weights: np.ndarray


def _constraints(
    deck: Deck, meshed: np.ndarray
) -> tuple[list[LinearConstraint], list[tuple[int, np.ndarray, np.ndarray]], list[FreeReference]]:
    """``*EQUATION`` cards as constraints on ccx node numbers (docs/method.md §13.1).

    ``meshed[row]``: the deck node belongs to an element (on any process). Terms are keyed
    ``3 node row + component``. Components of nodes in no element (reference
    nodes) with a ``*BOUNDARY`` somewhere are *prescribed*: returned apart as ``(constraint, keys,
    coefficients)``, their values become right-hand sides. The others are *free*: the first
    equation holding one expresses it by the equation's other terms (a :class:`FreeReference`)
    and is used up; the others get it substituted.
    """
    prescribed = {
        int(k)
        for card in (*deck.boundaries, *(b for step in deck.steps for b in step.boundaries))
        for k in (
            3 * deck.node_index(card.nodes)[:, None] + np.arange(card.first_dof - 1, card.last_dof)
        ).ravel()
    }
    equations = []  # (location, {key: coefficient} in term order)
    for equation in deck.equations:
        keys = 3 * deck.node_index(equation.nodes) + equation.dofs - 1
        terms: dict[int, float] = {}
        for key, a in zip(keys.tolist(), equation.coefficients.tolist()):
            terms[key] = terms.get(key, 0.0) + a
        equations.append((equation.location, terms))

    def free(key: int) -> bool:
        return not meshed[key // 3] and key not in prescribed

    loaded = {
        int(k)
        for step in deck.steps
        for card in step.cloads
        for k in 3 * deck.node_index(card.nodes) + card.dof - 1
    }
    references: list[FreeReference] = []
    used: set[int] = set()
    for key in dict.fromkeys(k for _, terms in equations for k in terms if free(k)):
        holders = [i for i, (_, terms) in enumerate(equations) if key in terms and i not in used]
        location, terms = equations[holders[0]]
        if [k for k in terms if free(k)] != [key]:
            raise ValueError(
                f"{location}: *EQUATION: more than one component of nodes in no element without "
                "a *BOUNDARY in one equation is not supported"
            )
        a = terms[key]
        weights = {k: -c / a for k, c in terms.items() if k != key}
        used.add(holders[0])
        for i in holders[1:]:
            _, other = equations[i]
            factor = other.pop(key)
            for k, w in weights.items():
                other[k] = other.get(k, 0.0) + factor * w
        mesh = [k for k in weights if meshed[k // 3]]
        refs = [k for k in weights if not meshed[k // 3]]
        references.append(
            FreeReference(
                key,
                np.array(mesh, dtype=np.int64),
                np.array([weights[k] for k in mesh]),
                np.array(refs, dtype=np.int64),
                np.array([weights[k] for k in refs]),
            )
        )
    constraints, reference_terms = [], []
    for i, (location, terms) in enumerate(equations):
        if i in used:
            continue
        keys = np.array(list(terms), dtype=np.int64)
        coefficients = np.array(list(terms.values()))
        mesh = meshed[keys // 3]
        if not np.any(mesh):
            raise ValueError(f"{location}: *EQUATION: no node of it belongs to an element")
        for key in keys[~mesh]:
            if int(key) in loaded:
                node = int(deck.node_ids[key // 3])
                raise ValueError(
                    f"{location}: *EQUATION node {node} belongs to no element and carries a "
                    "*CLOAD in a direction with a *BOUNDARY: not supported"
                )
        if not np.all(mesh):
            reference_terms.append((len(constraints), keys[~mesh], coefficients[~mesh]))
        constraints.append(
            LinearConstraint(
                deck.node_ids[keys[mesh] // 3], keys[mesh] % 3, coefficients[mesh],
                name=f"*EQUATION at {location}",
            )
        )  # fmt: skip
    return constraints, reference_terms, references
