"""Writer of CalculiX ``.inp`` decks: a contact problem built in Python, exported for ``ccx``.

``write_inp`` turns a dolfinx displacement space (P1 tetrahedra -> C3D4, P2 tetrahedra -> C3D10, P1
hexahedra -> C3D8), materials per cell tag, :class:`~dolfinx_ntf.ContactPair` objects, constraints,
loads and static steps into an equivalent ccx 2.20 deck, so that the same case runs in both codes
and ``read_deck`` reads it back.

Numbering and conventions shared by the whole module:
    - A *node* is a block dof of the displacement space (as everywhere in dolfinx_ntf); its ccx
      node number is its global block index + 1. A cell's element number is its global cell
      index + 1.
    - Node sets for constraints and loads are given as a :class:`~dolfinx_ntf.FacetSurface` (all
      nodes of those facets), a :class:`~dolfinx_ntf.NodeSurface` (its vertices) or an array of
      local block dofs of the space (e.g. from ``dolfinx.fem.locate_dofs_geometrical``).
    - Components are 0-based (0, 1, 2 = x, y, z); ccx dofs are 1-based.
    - Element node order follows ccx; cells whose dolfinx vertex order would give a negative ccx
      Jacobian are mirrored. Faces of :class:`~dolfinx_ntf.FacetSurface` objects become
      ``*SURFACE`` element faces S1..S6 (``*DLOAD`` P1..P6 for pressures).
    - Collective under MPI: every rank passes its local data, rank 0 writes the file.
    - Reals are written in their shortest round-trip form when it fits in ccx's 20-character fields
      (otherwise rounded to the 15-16 significant digits that fit).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import dolfinx.cpp.mesh
import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactPair
from dolfinx_ntf.fem.constraints import LinearConstraint
from dolfinx_ntf.fem.surfaces import FacetSurface, NodeSurface, facet_cells, resolve_slave
from dolfinx_ntf.kernels.laws import (
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    TabularLaw,
)

from .controls import FIELD_CONTROL_NAMES, TIGHT_FIELD_CONTROLS
from .elements import ELEMENT_TYPES, element_for_cell

__all__ = [
    "TIGHT_FIELD_CONTROLS",
    "AmplitudeSpec",
    "BoundarySpec",
    "InpNumbering",
    "NodeTarget",
    "OutputSpec",
    "PointLoadSpec",
    "PressureSpec",
    "StepSpec",
    "write_inp",
]

NodeTarget = FacetSurface | NodeSurface | np.ndarray | Sequence[int]
"""Nodes of a constraint or load: facets, vertices, or local block dofs of the space."""


@dataclass(frozen=True)
class BoundarySpec:
    """Fixed (``value = 0``) or prescribed displacement components of some nodes (``*BOUNDARY``).

    Attributes:
        nodes: The constrained nodes.
        components: 0-based displacement components (0, 1, 2 = x, y, z).
        value: Prescribed displacement of every listed component (reached at the end of the step,
            ramped as ccx ramps it, or scaled by the step's amplitude).
        name: Node-set name in the deck (default: generated).
    """

    nodes: NodeTarget
    components: Sequence[int] = (0, 1, 2)
    value: float = 0.0
    name: str | None = None


@dataclass(frozen=True)
class PressureSpec:
    """Uniform pressure on facets (``*DLOAD``, load type P1..P6): positive pushes into the body."""

    surface: FacetSurface
    value: float


@dataclass(frozen=True)
class PointLoadSpec:
    """Force ``value`` in direction ``component`` (0-based) on *each* of the nodes (``*CLOAD``)."""

    nodes: NodeTarget
    component: int
    value: float
    name: str | None = None


@dataclass(frozen=True)
class AmplitudeSpec:
    """Piecewise-linear load factor over step time (``*AMPLITUDE``)."""

    times: Sequence[float]
    values: Sequence[float]
    name: str = "AMP"


@dataclass(frozen=True)
class OutputSpec:
    """Print requests of a step (``*NODE PRINT``, ``*EL PRINT``, ``*CONTACT PRINT``).

    Attributes:
        node_print: ``*NODE PRINT`` keys (``U``, ``RF``); empty for none.
        node_set: Nodes of the node print (default: all nodes, set ``NALL``).
        el_print: ``*EL PRINT`` keys (``S``) for all elements; empty for none.
        contact_print: ``*CONTACT PRINT`` keys (``CDIS``, ``CSTR``, ``CELS``, ``CNUM``).
        contact_elements: Ask for the ``jobname.cel`` contact elements file.
        frequency: Print every ``frequency``-th increment (and the last one).
    """

    node_print: Sequence[str] = ("U",)
    node_set: NodeTarget | None = None
    el_print: Sequence[str] = ()
    contact_print: Sequence[str] = ("CDIS", "CSTR", "CELS", "CNUM")
    contact_elements: bool = False
    frequency: int = 1


@dataclass(frozen=True)
class StepSpec:
    """A static step (``*STEP``/``*STATIC``) with its boundary changes and loads.

    ccx rules apply: boundaries and loads of a step add to or change those of the previous steps
    (OP=MOD), and without an amplitude they ramp linearly over the step.

    Attributes:
        boundaries: Fixed or prescribed components introduced in this step.
        pressures: Face pressures.
        point_loads: Nodal forces.
        period: Step time.
        increments: Number of fixed increments (``DIRECT``, increment ``period/increments``);
            ``None`` for ccx's automatic incrementation from ``initial_increment``.
        initial_increment: First increment (automatic incrementation; default ``period``).
        min_increment, max_increment: Bounds of automatic increments (ccx defaults if None).
        nlgeom: Geometrically nonlinear step (St.Venant-Kirchhoff, follower pressure).
        amplitude: Load factor over step time for all boundaries and loads of the step.
        max_increments: The INC parameter (default ``max(100, increments)``).
        field_controls: ``*CONTROLS, PARAMETERS=FIELD`` values by name (``R_n``, ``C_n``, ``q_0``,
            ``q_u``, ``R_p``, ``epsilon``, ``C_epsilon``, ``R_l``); e.g. ``TIGHT_FIELD_CONTROLS``.
        time_controls: First data line of ``*CONTROLS, PARAMETERS=TIME INCREMENTATION`` (I_0, I_R,
            I_P, I_C, I_L, I_G, I_S, I_A; None leaves the field blank, i.e. ccx's default).
        output: Print requests.
        change_friction: New friction of pairs from this step on, by pair number (1-based, the
            order of ``pairs``): ``*CHANGE FRICTION`` of the pair's interaction ``SI<k>``.
        model_change: ``"ADD"`` or ``"REMOVE"`` by pair number: ``*MODEL CHANGE, TYPE=CONTACT
            PAIR``.
    """

    boundaries: Sequence[BoundarySpec] = ()
    pressures: Sequence[PressureSpec] = ()
    point_loads: Sequence[PointLoadSpec] = ()
    period: float = 1.0
    increments: int | None = 1
    initial_increment: float | None = None
    min_increment: float | None = None
    max_increment: float | None = None
    nlgeom: bool = False
    amplitude: AmplitudeSpec | None = None
    max_increments: int | None = None
    field_controls: Mapping[str, float] | None = None
    time_controls: Sequence[float | None] | None = None
    output: OutputSpec = field(default_factory=OutputSpec)
    change_friction: Mapping[int, object] = field(default_factory=dict)
    model_change: Mapping[int, str] = field(default_factory=dict)


@dataclass(frozen=True)
class InpNumbering:
    """ccx numbers of this rank's local nodes and cells (owned and ghost).

    Attributes:
        node_ids: ``(num_local_blocks_with_ghosts,)`` ccx node number of each block dof.
        element_ids: ``(num_local_cells_with_ghosts,)`` ccx element number of each cell.
        element_type: ``C3D4``, ``C3D10`` or ``C3D8``.
    """

    node_ids: np.ndarray
    element_ids: np.ndarray
    element_type: str


# ----------------------------------------------------------------------------- formatting


_FIELD_WIDTH = 20  # ccx reads reals from the first 20 characters of a field


def _real(value: float, what: str) -> str:
    """Shortest text that reads back as ``value``, else the closest that fits in 20 characters."""
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"{what} must be finite, got {value!r}")
    text = repr(x)
    digits = 17
    while len(text) > _FIELD_WIDTH:
        digits -= 1
        text = f"{x:.{digits}g}"
    return text


def _int_lines(ids: np.ndarray, per_line: int = 8) -> list[str]:
    ids = np.asarray(ids, dtype=np.int64).ravel()
    return [
        ", ".join(str(int(i)) for i in ids[k : k + per_line]) for k in range(0, ids.size, per_line)
    ]


def _name(text: str, what: str) -> str:
    name = "".join(str(text).split()).upper()
    if not name or len(name) > 80 or any(c in name for c in ",*=\"'"):
        raise ValueError(
            f"{what} {text!r} is not a valid ccx name (1-80 characters, no , * = or quotes)"
        )
    return name


def _check_type(value: object, cls: type, what: str) -> None:
    """Raise a ValueError naming ``what`` unless ``value`` is a ``cls``."""
    if not isinstance(value, cls):
        article = "an" if cls.__name__[0] in "AEIOU" else "a"
        raise ValueError(
            f"write_inp: {what} must be {article} {cls.__name__}, got {type(value).__name__}"
        )


# ----------------------------------------------------------------------------- mesh


def _element_type(V: dolfinx.fem.FunctionSpace) -> str:
    mesh = V.mesh
    if V.dofmap.index_map_bs != 3 or mesh.geometry.dim != 3 or mesh.topology.dim != 3:
        raise ValueError(
            "write_inp needs a 3D vector displacement space (block size 3) on a 3D mesh"
        )
    family = compat.space_family(V)
    degree = compat.space_degree(V)
    if family not in ("Lagrange", "Q", "P", "CG"):
        raise ValueError(
            f"write_inp: displacement space family {family!r} has no ccx element; use Lagrange"
        )
    cell = mesh.topology.cell_type
    etype = element_for_cell(cell.name, degree)
    if etype is not None:
        return etype.name
    raise ValueError(
        f"write_inp: no ccx element for degree-{degree} Lagrange on {cell.name} cells (supported: "
        "P1/P2 tetrahedra -> C3D4/C3D10, P1 hexahedra -> C3D8; 27-node hexahedra are not ccx's "
        "C3D20)"
    )


def _signed_volume(x: np.ndarray, etype: str) -> np.ndarray:
    """Sign-carrying Jacobian of cells ``x (C, k, 3)`` in ccx corner order."""
    if ELEMENT_TYPES[etype].cell == "hexahedron":
        dxi = x[:, [1, 2, 6, 5]].sum(axis=1) - x[:, [0, 3, 7, 4]].sum(axis=1)
        deta = x[:, [3, 2, 6, 7]].sum(axis=1) - x[:, [0, 1, 5, 4]].sum(axis=1)
        dzeta = x[:, 4:8].sum(axis=1) - x[:, 0:4].sum(axis=1)
    else:
        dxi, deta, dzeta = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0], x[:, 3] - x[:, 0]
    return np.einsum("ci,ci->c", np.cross(dxi, deta), dzeta)


def _local_node_order(V: dolfinx.fem.FunctionSpace, etype: str) -> tuple[np.ndarray, np.ndarray]:
    """Per orientation: ccx element node -> cell-local dof, and dolfinx vertex -> ccx corner."""
    table = ELEMENT_TYPES[etype]
    corners = (table.corner_vertices, table.mirrored_vertices)
    if not table.midside_edges:
        orders = [c for c in corners]
    else:
        layout = V.dofmap.dof_layout
        cell_type = V.mesh.topology.cell_type
        edge_vertices = dolfinx.cpp.mesh.get_entity_vertices(cell_type, 1)
        edge_dof = {}
        for e in range(dolfinx.cpp.mesh.cell_num_entities(cell_type, 1)):
            a, b = (int(v) for v in edge_vertices.links(e))
            edge_dof[frozenset((a, b))] = int(layout.entity_dofs(1, e)[0])
        orders = []
        for c in corners:
            mids = [edge_dof[frozenset((int(c[a]), int(c[b])))] for a, b in table.midside_edges]
            orders.append(np.concatenate([c, mids]))
    vertex_to_corner = []
    for c in corners:
        inverse = np.empty(c.size, dtype=np.int64)
        inverse[c] = np.arange(c.size)
        vertex_to_corner.append(inverse)
    return np.array(orders), np.array(vertex_to_corner)


@dataclass
class _Mesh:
    """Local (this rank's owned) mesh data in ccx numbering."""

    etype: str
    node_ids: np.ndarray  # (blocks with ghosts,) ccx ids
    element_ids: np.ndarray  # (cells with ghosts,) ccx ids
    num_owned_nodes: int
    num_owned_cells: int
    coords: np.ndarray  # (owned nodes, 3)
    connectivity: np.ndarray  # (owned cells, k) ccx node ids in ccx order
    mirrored: np.ndarray  # (owned cells,) bool
    face_of_facet: np.ndarray  # (2, num facets per cell) ccx face number (1-based) per orientation


def _node_coordinates(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Coordinates of every block dof (owned and ghost), ``(num_blocks, 3)``.

    Dofs on cell vertices take the mesh's own geometry nodes, and P2 midside dofs of a
    straight-sided mesh the mean of their edge's two nodes, so that coordinates given exactly (a
    structured grid, nodes placed above other nodes) reach the deck without the round-off of the
    reference-to-physical map. Other dofs (on a curved mesh) are tabulated.
    """
    X = V.tabulate_dof_coordinates().reshape(-1, 3).copy()
    mesh = V.mesh
    x = mesh.geometry.x
    dofs, nodes = compat.cell_dofs(V), compat.geometry_dofs(mesh)
    layout = V.dofmap.dof_layout
    cell_type = mesh.topology.cell_type
    num_vertices = dolfinx.cpp.mesh.cell_num_entities(cell_type, 0)
    for vertex in range(num_vertices):  # 4 or 8 vertices
        X[dofs[:, layout.entity_dofs(0, vertex)[0]]] = x[nodes[:, vertex]]
    if nodes.shape[1] == num_vertices:
        edges = dolfinx.cpp.mesh.get_entity_vertices(cell_type, 1)
        for edge in range(dolfinx.cpp.mesh.cell_num_entities(cell_type, 1)):  # 6 or 12 edges
            if len(layout.entity_dofs(1, edge)) == 1:
                a, b = (int(v) for v in edges.links(edge))
                midside = dofs[:, layout.entity_dofs(1, edge)[0]]
                X[midside] = 0.5 * (x[nodes[:, a]] + x[nodes[:, b]])
    return X


def _mesh_data(V: dolfinx.fem.FunctionSpace) -> _Mesh:
    etype = _element_type(V)
    mesh = V.mesh
    tdim = 3
    imap = V.dofmap.index_map
    num_blocks = imap.size_local + imap.num_ghosts
    node_ids = imap.local_to_global(np.arange(num_blocks, dtype=np.int32)).astype(np.int64) + 1
    cmap = mesh.topology.index_map(tdim)
    num_cells = cmap.size_local + cmap.num_ghosts
    element_ids = cmap.local_to_global(np.arange(num_cells, dtype=np.int32)).astype(np.int64) + 1
    cell_dofs = compat.cell_dofs(V)[: cmap.size_local]
    X = _node_coordinates(V)
    orders, vertex_to_corner = _local_node_order(V, etype)
    ncorners = ELEMENT_TYPES[etype].num_corners
    local = cell_dofs[:, orders[0]]
    mirrored = _signed_volume(X[local[:, :ncorners]], etype) < 0
    local[mirrored] = cell_dofs[mirrored][:, orders[1]]
    if np.any(_signed_volume(X[local[:, :ncorners]], etype) <= 0):
        bad = int(np.flatnonzero(_signed_volume(X[local[:, :ncorners]], etype) <= 0)[0])
        x = X[local[bad, :ncorners]].mean(axis=0)
        raise ValueError(
            f"write_inp: cell {bad} at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}) is degenerate"
        )

    # ccx face number of each dolfinx local facet, for both orientations (bit masks of ccx corners).
    cell_type = mesh.topology.cell_type
    facet_vertices = dolfinx.cpp.mesh.get_entity_vertices(cell_type, tdim - 1)
    num_facets = dolfinx.cpp.mesh.cell_num_entities(cell_type, tdim - 1)
    ccx_faces = ELEMENT_TYPES[etype].faces[:, : ELEMENT_TYPES[etype].face_corners]
    face_by_mask = {int(np.sum(1 << f)): k + 1 for k, f in enumerate(ccx_faces)}
    face_of_facet = np.array(
        [
            [
                face_by_mask[int(np.sum(1 << v2c[facet_vertices.links(f)]))]
                for f in range(num_facets)
            ]
            for v2c in vertex_to_corner
        ]
    )
    return _Mesh(
        etype,
        node_ids,
        element_ids,
        imap.size_local,
        cmap.size_local,
        X[: imap.size_local],
        node_ids[local],
        mirrored,
        face_of_facet,
    )


# ----------------------------------------------------------------------------- sets and faces


def _tagged_facets(comm, surface: FacetSurface, what: str) -> np.ndarray:
    """Local facets of a facet surface; every tag value must exist on some rank."""
    if not isinstance(surface, FacetSurface):
        raise ValueError(f"{what}: expected a FacetSurface, got {type(surface).__name__}")
    tags = surface.tags
    if tags.dim != 2:
        raise ValueError(
            f"{what}: MeshTags of dimension {tags.dim} given, facet tags (dimension 2) needed"
        )
    values = surface.value_list()
    present = set().union(*comm.allgather(set(np.unique(tags.values).tolist())))
    missing = [v for v in values if v not in present]
    if missing:
        raise ValueError(
            f"{what}: facet tag value(s) {missing} not found in the facet tags "
            f"(values present: {sorted(present)})"
        )
    return tags.indices[np.isin(tags.values, values)].astype(np.int32)


def _facet_faces(
    V: dolfinx.fem.FunctionSpace, md: _Mesh, surface: FacetSurface, what: str
) -> tuple[np.ndarray, np.ndarray]:
    """Element ids and ccx face numbers (1-based) of the facets of ``surface`` in owned cells."""
    mesh = V.mesh
    facets = _tagged_facets(mesh.comm, surface, what)
    cells, local_facet = facet_cells(mesh, facets, what)
    owned = cells < md.num_owned_cells
    cells, local_facet = cells[owned], local_facet[owned]
    faces = md.face_of_facet[md.mirrored[cells].astype(np.int64), local_facet]
    return md.element_ids[cells], faces


def _node_ids(V: dolfinx.fem.FunctionSpace, md: _Mesh, target: NodeTarget, what: str) -> np.ndarray:
    """Sorted unique ccx ids of the owned nodes of a node target (not empty over all ranks)."""
    mesh = V.mesh
    if isinstance(target, FacetSurface):
        facets = _tagged_facets(mesh.comm, target, what)
        mesh.topology.create_connectivity(2, 3)
        blocks = dolfinx.fem.locate_dofs_topological(V, 2, facets)
    elif isinstance(target, NodeSurface):
        blocks = resolve_slave(V, target, what=what).nodes
    else:
        blocks = np.asarray(target)
        if blocks.ndim != 1 or (blocks.size and not np.issubdtype(blocks.dtype, np.integer)):
            raise ValueError(
                f"{what}: nodes must be a FacetSurface, a NodeSurface or a 1-D integer array of "
                f"block dofs, got {type(target).__name__} of shape {blocks.shape}"
            )
        if blocks.size and (blocks.min() < 0 or blocks.max() >= md.node_ids.size):
            raise ValueError(f"{what}: block dof indices outside 0..{md.node_ids.size - 1}")
    blocks = np.asarray(blocks, dtype=np.int64)
    blocks = blocks[blocks < md.num_owned_nodes]
    ids = np.unique(md.node_ids[blocks])
    if mesh.comm.allreduce(ids.size) == 0:
        raise ValueError(f"{what}: the node set is empty")
    return ids


def _components(components: Sequence[int], what: str) -> list[tuple[int, int]]:
    """Contiguous 1-based ccx dof ranges of 0-based components."""
    comps = sorted({int(c) for c in components})
    if not comps or comps[0] < 0 or comps[-1] > 2:
        raise ValueError(
            f"{what}: components must be a non-empty subset of (0, 1, 2), got {components!r}"
        )
    ranges: list[tuple[int, int]] = []
    for c in comps:
        if ranges and ranges[-1][1] == c:
            ranges[-1] = (ranges[-1][0], c + 1)
        else:
            ranges.append((c + 1, c + 1))
    return ranges


# ----------------------------------------------------------------------------- contact


def _law_lines(law: PressureOverclosureLaw, what: str) -> list[str]:
    if isinstance(law, ExponentialLaw):
        return [
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL",
            f"{_real(law.c0, what)}, {_real(law.p0, what)}",
        ]
    if isinstance(law, LinearLaw):
        return [
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
            f"{_real(law.slope, what)}, {_real(law.tension, what)}, {_real(law.c0, what)}",
        ]
    if isinstance(law, TabularLaw):
        return ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=TABULAR"] + [
            f"{_real(p, what)}, {_real(d, what)}" for p, d in zip(law.pressures, law.overclosures)
        ]
    raise ValueError(f"{what}: no ccx *SURFACE BEHAVIOR for law {law!r}")


# ----------------------------------------------------------------------------- writer


class _Out:
    """Deck lines, kept on rank 0, and the names already used for node sets."""

    def __init__(self, comm) -> None:
        self.comm = comm
        self.lines: list[str] = []
        self.set_names: set[str] = {"NALL", "EALL"}

    def gather(self, array: np.ndarray) -> np.ndarray:
        """Concatenation of every rank's ``array`` on rank 0 (an empty slice elsewhere)."""
        array = np.asarray(array)
        parts = self.comm.gather(array, root=0)
        if self.comm.rank != 0:
            return array[:0]
        return np.concatenate(parts)

    def add(self, *lines: str) -> None:
        if self.comm.rank == 0:
            self.lines.extend(lines)

    def nset(self, name: str | None, default: str, ids: np.ndarray, what: str) -> str:
        """Write ``*NSET`` of the (gathered) ``ids``; returns the set name."""
        name = _name(name, f"{what} name") if name else default
        if name in self.set_names:
            raise ValueError(f"write_inp: {what}: node set name {name} is used twice")
        self.set_names.add(name)
        self.add(f"*NSET, NSET={name}", *_int_lines(np.unique(self.gather(ids))))
        return name


def write_inp(
    path: str | Path,
    *,
    displacement_space: dolfinx.fem.FunctionSpace,
    materials: tuple[float, float] | Mapping[int, tuple[float, float]],
    cell_tags: compat.MeshTags | None = None,
    pairs: Sequence[ContactPair] = (),
    fixed: Sequence[BoundarySpec] = (),
    steps: Sequence[StepSpec] = (StepSpec(),),
    heading: str = "dolfinx_ntf deck",
    constraints: Sequence[LinearConstraint] = (),
) -> InpNumbering:
    """Write a ccx deck equivalent to a contact problem built in Python. Collective.

    Args:
        path: The ``.inp`` file to write (on rank 0).
        displacement_space: Vector Lagrange space of the displacement: P1 or P2 on tetrahedra, P1 on
            hexahedra. Its mesh is the ccx mesh and its nodes are the ccx nodes.
        materials: Isotropic ``(E, nu)`` of every cell, or a mapping cell-tag value -> ``(E, nu)``.
        cell_tags: Cell tags selecting the material of each cell (needed with a mapping).
        pairs: Contact pairs, written as ``*CONTACT PAIR, TYPE=NODE TO SURFACE`` in this order (ccx
            numbers contact elements pair by pair). Laws: EXPONENTIAL, LINEAR, TABULAR; friction
            as ``*FRICTION``.
        fixed: Constraints of the model definition (before the first step), normally zero values.
        steps: Static steps with their own boundaries, loads, incrementation, controls and output.
        heading: ``*HEADING`` text.
        constraints: Linear constraints, written as ``*EQUATION`` cards in their term order (ccx
            makes the first term dependent: it must have no ``*BOUNDARY``); one process only.

    Returns:
        The ccx numbers of this rank's nodes and cells, to compare ccx results with dolfinx ones.

    Raises:
        ValueError: Unsupported space or law, bad material, missing tags, empty node sets, bad
            steps.

    Example:
        A punch (cell tag 2) pressed on a block (tag 1) in four fixed increments, ccx's
        tolerances tightened to compare with ``run_job(..., tight=True)``::

            write_inp("job.inp", displacement_space=V, materials={1: (E, nu), 2: (E, nu)},
                      cell_tags=cell_tags, pairs=[pair],
                      fixed=[BoundarySpec(FacetSurface(facet_tags, BOTTOM))],
                      steps=[StepSpec(pressures=[PressureSpec(FacetSurface(facet_tags, TOP), 10.0)],
                                      increments=4, field_controls=TIGHT_FIELD_CONTROLS)])
    """
    V = displacement_space
    md = _mesh_data(V)
    out = _Out(V.mesh.comm)
    if not steps:
        raise ValueError("write_inp: at least one step is needed")
    out.add(
        "*HEADING",
        *(line if line.strip() else "**" for line in str(heading).splitlines() or ["**"]),
    )

    _write_mesh(out, md, materials, cell_tags)
    for k, pair in enumerate(pairs, start=1):
        _write_pair(out, V, md, k, pair)
    _write_amplitudes(out, steps)

    _write_equations(out, md, constraints)
    # Node sets are model definition: write all of them before the first step.
    if fixed:
        cards = [
            _boundary_card(out, V, md, b, f"fixed boundary {i}", f"FIX{i}")
            for i, b in enumerate(fixed, start=1)
        ]
        out.add("*BOUNDARY", *(line for card in cards for line in card))
    step_cards = [_step_sets(out, V, md, s, step) for s, step in enumerate(steps, start=1)]
    for s, (step, cards) in enumerate(zip(steps, step_cards), start=1):
        _write_step(out, s, step, *cards)

    if out.comm.rank == 0:
        Path(path).write_text("\n".join(out.lines) + "\n")
    return InpNumbering(md.node_ids.copy(), md.element_ids.copy(), md.etype)


def _write_equations(out: _Out, md: _Mesh, constraints: Sequence[LinearConstraint]) -> None:
    """``*EQUATION``: per constraint its number of terms, then 4 (node, dof, coefficient) a line."""
    if not constraints:
        return
    if out.comm.size > 1:
        raise NotImplementedError("write_inp: constraints are written on one process only")
    lines = []
    for c in constraints:
        _check_type(c, LinearConstraint, "write_inp: constraints")
        if c.value != 0.0:
            raise ValueError(f"write_inp: {c.label}: ccx's *EQUATION has a zero right-hand side")
        terms = [
            f"{int(md.node_ids[n])},{int(k) + 1},{_real(a, 'an *EQUATION coefficient')}"
            for n, k, a in zip(c.nodes, c.components, c.coefficients)
        ]
        lines.append(str(len(terms)))
        lines += [",".join(terms[i : i + 4]) for i in range(0, len(terms), 4)]
    out.add("*EQUATION", *lines)


def _write_mesh(out: _Out, md: _Mesh, materials, cell_tags) -> None:
    ids = out.gather(md.node_ids[: md.num_owned_nodes])
    xyz = out.gather(md.coords)
    order = np.argsort(ids)
    coordinates = np.vectorize(lambda x: _real(x, "node coordinate"), otypes=[object])(xyz[order])
    out.add(
        "*NODE, NSET=NALL",
        *(f"{i}, {x}, {y}, {z}" for i, (x, y, z) in zip(ids[order].tolist(), coordinates.tolist())),
    )
    groups = _material_groups(out.comm, md, materials, cell_tags)
    for name, (cells, _) in groups.items():
        eids = out.gather(md.element_ids[cells])
        conn = out.gather(md.connectivity[cells])
        order = np.argsort(eids)
        rows = np.column_stack([eids[order], conn[order]]).tolist()
        out.add(f"*ELEMENT, TYPE={md.etype}, ELSET={name}", *(", ".join(map(str, r)) for r in rows))
    names = list(groups)
    out.add("*ELSET, ELSET=EALL", *(", ".join(names[k : k + 8]) for k in range(0, len(names), 8)))
    for name, (_, (young, nu)) in groups.items():
        out.add(
            f"*MATERIAL, NAME=M_{name}",
            "*ELASTIC",
            f"{_real(young, 'E')}, {_real(nu, 'nu')}",
            f"*SOLID SECTION, ELSET={name}, MATERIAL=M_{name}",
        )


def _material_groups(
    comm, md: _Mesh, materials, cell_tags
) -> dict[str, tuple[np.ndarray, tuple[float, float]]]:
    """Element set name -> (owned cells, (E, nu)), checked."""

    def elastic(values, what: str) -> tuple[float, float]:
        try:
            young, nu = (float(v) for v in values)
        except (TypeError, ValueError):
            raise ValueError(f"write_inp: {what} must be (E, nu), got {values!r}") from None
        if not (math.isfinite(young) and young > 0 and -1 < nu < 0.5):
            raise ValueError(
                f"write_inp: {what} needs E > 0 and -1 < nu < 0.5, got ({young}, {nu})"
            )
        return young, nu

    if not isinstance(materials, Mapping):
        return {"SOLID": (np.arange(md.num_owned_cells), elastic(materials, "materials"))}
    if cell_tags is None:
        raise ValueError("write_inp: materials per cell tag need cell_tags")
    if cell_tags.dim != 3:
        raise ValueError(
            f"write_inp: cell_tags have dimension {cell_tags.dim}, cell tags (dimension 3) needed"
        )
    tag_of_cell = np.full(md.num_owned_cells, -1, dtype=np.int64)
    keep = cell_tags.indices < md.num_owned_cells
    tag_of_cell[cell_tags.indices[keep]] = cell_tags.values[keep]
    tags = sorted(int(t) for t in materials)
    unknown = np.flatnonzero(~np.isin(tag_of_cell, tags))
    if comm.allreduce(unknown.size):
        if unknown.size:
            bad = int(unknown[0])
            tag = "no tag" if tag_of_cell[bad] < 0 else f"tag {int(tag_of_cell[bad])}"
            message = f"cell {bad} (rank {comm.rank}) has {tag}"
        else:
            message = "a cell on another rank has no material"
        raise ValueError(f"write_inp: {message}, and materials are given for tags {tags} only")
    return {
        f"E{tag}": (
            np.flatnonzero(tag_of_cell == tag),
            elastic(materials[tag], f"material of tag {tag}"),
        )
        for tag in tags
    }


def _write_pair(out: _Out, V, md: _Mesh, k: int, pair: ContactPair) -> None:
    what = f"contact pair {k}" + (f" ({pair.name})" if getattr(pair, "name", "") else "")
    _check_type(pair, ContactPair, what)
    if not pair.active:
        raise ValueError(f"write_inp: {what} is inactive; ccx pairs are active from the first step")
    slave, master = f"SLAVE{k}", f"MASTER{k}"
    if isinstance(pair.slave, NodeSurface):
        ids = np.unique(out.gather(_node_ids(V, md, pair.slave, f"{what} slave")))
        out.add(
            f"*SURFACE, NAME={slave}, TYPE=NODE", *map(str, ids.tolist())
        )  # ccx: one node per line
    else:
        _write_face_surface(out, V, md, slave, pair.slave, f"{what} slave")
    if not isinstance(pair.master, FacetSurface):  # node-based or rigid (docs/method.md §15.1)
        raise ValueError(
            f"write_inp: {what}: the master surface must be a FacetSurface (face-based); "
            f"CalculiX decks have no {type(pair.master).__name__}"
        )
    _write_face_surface(out, V, md, master, pair.master, f"{what} master")
    small = ", SMALL SLIDING" if pair.small_sliding else ""
    if isinstance(pair.adjust, NodeSurface):
        ids = np.unique(out.gather(_node_ids(V, md, pair.adjust, f"{what} adjust")))
        out.add(f"*NSET, NSET=ADJUST{k}", *_int_lines(ids))
        small += f", ADJUST=ADJUST{k}"
    elif pair.adjust is not None:
        small += f", ADJUST={_real(pair.adjust, 'adjust')}"
    out.add(
        f"*CONTACT PAIR, INTERACTION=SI{k}, TYPE=NODE TO SURFACE{small}",
        f"{slave}, {master}",
        f"*SURFACE INTERACTION, NAME=SI{k}",
        *_law_lines(pair.interaction.law, f"write_inp: {what}"),
        *_friction_lines(pair.interaction.friction),
    )


def _friction_lines(friction: Friction | None) -> list[str]:
    """``*FRICTION`` card of a :class:`~dolfinx_ntf.Friction` (none for ``None``)."""
    if friction is None:
        return []
    return [
        "*FRICTION",
        f"{_real(friction.mu, 'mu')}, {_real(friction.stick_slope, 'stick slope')}",
    ]


def _write_face_surface(out: _Out, V, md: _Mesh, name: str, surface, what: str) -> None:
    elements, faces = _facet_faces(V, md, surface, f"write_inp: {what}")
    elements, faces = out.gather(elements), out.gather(faces)
    order = np.lexsort((faces, elements))
    out.add(
        f"*SURFACE, NAME={name}",
        *(f"{e}, S{f}" for e, f in zip(elements[order].tolist(), faces[order].tolist())),
    )


def _write_amplitudes(out: _Out, steps: Sequence[StepSpec]) -> None:
    amplitudes: dict[str, AmplitudeSpec] = {}
    for s, step in enumerate(steps, start=1):
        amp = step.amplitude
        if amp is None:
            continue
        name = _name(amp.name, f"step {s} amplitude name")
        if name in amplitudes and amplitudes[name] is not amp:
            raise ValueError(f"write_inp: two different amplitudes are named {name} (step {s})")
        amplitudes[name] = amp
    for name, amp in amplitudes.items():
        t = np.asarray(amp.times, dtype=float).ravel()
        a = np.asarray(amp.values, dtype=float).ravel()
        if t.size == 0 or t.shape != a.shape or np.any(np.diff(t) < 0):
            raise ValueError(
                f"write_inp: amplitude {name} needs as many values as times, times non-decreasing"
            )
        items = [
            f"{_real(ti, 'amplitude time')}, {_real(ai, 'amplitude value')}" for ti, ai in zip(t, a)
        ]
        out.add(
            f"*AMPLITUDE, NAME={name}",
            *(", ".join(items[k : k + 4]) for k in range(0, len(items), 4)),
        )


def _boundary_card(
    out: _Out, V, md: _Mesh, boundary: BoundarySpec, what: str, default: str
) -> list[str]:
    """Write the node set of a boundary; returns its ``*BOUNDARY`` data lines."""
    _check_type(boundary, BoundarySpec, what)
    ranges = _components(boundary.components, f"write_inp: {what}")
    value = _real(boundary.value, f"write_inp: {what} value")
    name = out.nset(
        boundary.name, default, _node_ids(V, md, boundary.nodes, f"write_inp: {what}"), what
    )
    return [f"{name}, {a}, {b}, {value}" for a, b in ranges]


def _step_sets(
    out: _Out, V, md: _Mesh, s: int, step: StepSpec
) -> tuple[list[str], list[str], list[str]]:
    """Write the node sets of a step; return its ``*BOUNDARY``, ``*CLOAD`` and ``*DLOAD`` lines."""
    _check_type(step, StepSpec, f"step {s}")
    boundaries = [
        line
        for i, b in enumerate(step.boundaries, start=1)
        for line in _boundary_card(out, V, md, b, f"step {s} boundary {i}", f"S{s}B{i}")
    ]
    cloads = []
    for i, load in enumerate(step.point_loads, start=1):
        what = f"step {s} point load {i}"
        _check_type(load, PointLoadSpec, what)
        if load.component not in (0, 1, 2):
            raise ValueError(
                f"write_inp: {what}: component must be 0, 1 or 2, got {load.component!r}"
            )
        value = _real(load.value, f"write_inp: {what} value")
        name = out.nset(
            load.name, f"S{s}C{i}", _node_ids(V, md, load.nodes, f"write_inp: {what}"), what
        )
        cloads.append(f"{name}, {int(load.component) + 1}, {value}")
    dloads = []
    for i, pressure in enumerate(step.pressures, start=1):
        what = f"step {s} pressure {i}"
        _check_type(pressure, PressureSpec, what)
        value = _real(pressure.value, f"write_inp: {what} value")
        elements, faces = _facet_faces(V, md, pressure.surface, f"write_inp: {what}")
        elements, faces = out.gather(elements), out.gather(faces)
        order = np.lexsort((faces, elements))
        dloads.extend(
            f"{e}, P{f}, {value}" for e, f in zip(elements[order].tolist(), faces[order].tolist())
        )
    if step.output.node_set is not None and step.output.node_print:
        ids = _node_ids(V, md, step.output.node_set, f"write_inp: step {s} output node set")
        out.nset(None, f"S{s}OUT", ids, f"step {s} output node set")
    return boundaries, cloads, dloads


def _static_line(s: int, step: StepSpec) -> tuple[str, str, int]:
    """Return the ``*STATIC`` parameter, its data line and the INC parameter of a step."""
    period = float(step.period)
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"write_inp: step {s}: period must be > 0, got {step.period!r}")
    if step.increments is not None:
        n = int(step.increments)
        if n < 1 or n != step.increments:
            raise ValueError(
                f"write_inp: step {s}: increments must be an integer >= 1, got {step.increments!r}"
            )
        line = f"{_real(period / n, 'increment')}, {_real(period, 'period')}"
        return ", DIRECT", line, int(step.max_increments or max(100, n))
    initial = period if step.initial_increment is None else float(step.initial_increment)
    if not 0 < initial <= period:
        raise ValueError(
            f"write_inp: step {s}: need 0 < initial_increment <= period, got {initial}"
        )
    fields = [
        _real(initial, "initial increment"),
        _real(period, "period"),
        "" if step.min_increment is None else _real(step.min_increment, "min_increment"),
        "" if step.max_increment is None else _real(step.max_increment, "max_increment"),
    ]
    while fields[-1] == "":
        fields.pop()
    return "", ", ".join(fields), int(step.max_increments or 100)


def _write_step(
    out: _Out, s: int, step: StepSpec, boundaries: list[str], cloads: list[str], dloads: list[str]
) -> None:
    direct, static, inc = _static_line(s, step)
    out.add(
        f"*STEP, NLGEOM={'YES' if step.nlgeom else 'NO'}, INC={inc}", f"*STATIC{direct}", static
    )
    if step.field_controls is not None:
        unknown = sorted(set(step.field_controls) - set(FIELD_CONTROL_NAMES))
        if unknown:
            raise ValueError(
                f"write_inp: step {s}: unknown field control(s) {unknown} (known: "
                f"{', '.join(FIELD_CONTROL_NAMES)})"
            )
        values = [
            "" if step.field_controls.get(k) is None else _real(step.field_controls[k], k)
            for k in FIELD_CONTROL_NAMES
        ]
        while values[-1] == "":
            values.pop()
        out.add("*CONTROLS, PARAMETERS=FIELD", ", ".join(values))
    if step.time_controls is not None:
        values = ["" if v is None else str(int(v)) for v in step.time_controls]
        out.add("*CONTROLS, PARAMETERS=TIME INCREMENTATION", ", ".join(values))
    amp = (
        f", AMPLITUDE={_name(step.amplitude.name, 'amplitude name')}"
        if step.amplitude is not None
        else ""
    )
    for k, friction in sorted(step.change_friction.items()):
        out.add(f"*CHANGE FRICTION, INTERACTION=SI{int(k)}", *_friction_lines(friction))
    for k, action in sorted(step.model_change.items()):
        if action not in ("ADD", "REMOVE"):
            raise ValueError(f"write_inp: step {s}: model_change {action!r}: ADD or REMOVE")
        out.add(f"*MODEL CHANGE, TYPE=CONTACT PAIR, {action}", f"SLAVE{int(k)}, MASTER{int(k)}")
    if boundaries:
        out.add(f"*BOUNDARY{amp}", *boundaries)
    if cloads:
        out.add(f"*CLOAD{amp}", *cloads)
    if dloads:
        out.add(f"*DLOAD{amp}", *dloads)
    _write_output(out, s, step.output)
    out.add("*END STEP")


def _write_output(out: _Out, s: int, output: OutputSpec) -> None:
    _check_type(output, OutputSpec, f"step {s} output")
    frequency = int(output.frequency)
    if frequency < 1:
        raise ValueError(
            f"write_inp: step {s}: output frequency must be >= 1, got {output.frequency!r}"
        )
    fpar = f", FREQUENCY={frequency}" if frequency != 1 else ""
    requests = (
        ("node_print", output.node_print, ("U", "RF")),
        ("el_print", output.el_print, ("S",)),
        ("contact_print", output.contact_print, ("CDIS", "CSTR", "CELS", "CNUM")),
    )
    keys = {}
    for what, given, allowed in requests:
        keys[what] = [str(k).upper() for k in given]
        bad = [k for k in keys[what] if k not in allowed]
        if bad:
            raise ValueError(
                f"write_inp: step {s}: {what} keys {bad} not supported (use {', '.join(allowed)})"
            )
    if keys["node_print"]:
        node_set = "NALL" if output.node_set is None else f"S{s}OUT"
        out.add(f"*NODE PRINT, NSET={node_set}{fpar}", ", ".join(keys["node_print"]))
    if keys["el_print"]:
        out.add(f"*EL PRINT, ELSET=EALL{fpar}", ", ".join(keys["el_print"]))
    if keys["contact_print"]:
        out.add(f"*CONTACT PRINT{fpar}", ", ".join(keys["contact_print"]))
    if output.contact_elements:
        out.add(f"*NODE FILE, CONTACT ELEMENTS{fpar}", "U")
