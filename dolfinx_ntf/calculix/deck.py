"""Reader of CalculiX ``.inp`` decks: the subset needed for node-to-face contact.

See docs/method.md §8.5.

``read_deck`` turns a deck (with its ``*INCLUDE`` files) into a ``Deck`` of frozen dataclasses
that keeps CalculiX's node and element numbers, so that results can be reported per ccx node. Only
the keywords that a static node-to-surface contact analysis needs are understood; everything else
is rejected with a ``DeckError`` (a ``ValueError``) naming the keyword and ``file:line``, except
the keywords and parameters that cannot change the solution (output-only ones, those ccx itself
ignores): ``LENIENCY`` lists them, the reader skips them with one ``DeckWarning`` each in
``Deck.warnings`` (skipped keywords are also in ``Deck.ignored``), as ccx warns and goes on.

Conventions shared by the whole module (they follow ccx, manual §"Input deck format"):
    - Keywords, parameters and names are case-insensitive and blanks are not significant: every
      name (sets, surfaces, materials, interactions, amplitudes) is stored upper-case without
      blanks, as ccx prints them. Only ``*HEADING`` text and ``*INCLUDE`` file names keep their
      case.
    - Node and element sets keep their members in definition order, duplicates included (ccx
      prints ``*NODE PRINT`` rows in that order). Set names must be defined before they are
      used; node and element *numbers* may be defined anywhere and are checked at the end.
    - Element types and their face tables are in ``calculix.elements`` (ccx's internal face
      order, outward normals).
    - Pure Python/numpy: no dolfinx import.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .elements import ELEMENT_TYPES, ElementType

__all__ = [
    "ELEMENT_TYPES",
    "FIELD_CONTROL_DEFAULTS",
    "FIELD_CONTROL_NAMES",
    "LENIENCY",
    "Amplitude",
    "Boundary",
    "CLoad",
    "ContactPair",
    "DLoad",
    "Deck",
    "DeckError",
    "DeckWarning",
    "Dynamic",
    "ElementBlock",
    "ElementType",
    "Equation",
    "FileRequest",
    "Friction",
    "FrictionChange",
    "InitialVelocity",
    "Location",
    "Material",
    "ModelChange",
    "PrintRequest",
    "SolidSection",
    "Static",
    "Step",
    "Surface",
    "SurfaceBehavior",
    "SurfaceInteraction",
    "external_faces",
    "face_nodes",
    "node_surface_faces",
    "read_deck",
    "surface_nodes",
]


# ----------------------------------------------------------------------------- errors, locations


@dataclass(frozen=True)
class Location:
    """A line of a deck file (1-based), printed as ``file:line``."""

    file: str
    line: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"


class DeckError(ValueError):
    """Bad or unsupported deck input; the message starts with ``file:line``."""

    def __init__(self, message: str, location: Location | None = None) -> None:
        self.location = location
        super().__init__(f"{location}: {message}" if location is not None else message)


# ----------------------------------------------------------------------------- element types


@dataclass(frozen=True)
class DeckWarning:
    """A keyword or parameter that was read and skipped because it cannot change the solution.

    Attributes:
        keyword: the keyword as ccx spells it (``*EL FILE``).
        parameter: the parameter as written (``POSITION=NODES``), or None for the whole keyword.
        reason: why skipping it is safe.
        location: where the card is.
    """

    keyword: str
    parameter: str | None
    reason: str
    location: Location

    def __str__(self) -> str:
        what = "keyword" if self.parameter is None else f"parameter {self.parameter}"
        return (
            f" *WARNING reading {self.keyword}: {what} ignored ({self.reason}) at {self.location}"
        )


#: Why some common ccx elements are refused (appended to the refusal).
_REFUSED_ELEMENTS = {
    "C3D8R": ": its one-point integration with hourglass control is not reproduced",
    "C3D8I": ": its incompatible modes (extra internal displacement fields) are not reproduced",
}


# ----------------------------------------------------------------------------- data model


def _frozen_array(values, dtype) -> np.ndarray:
    array = np.array(values, dtype=dtype)
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class ElementBlock:
    """All elements of one type: ``ids (E,)`` and ``connectivity (E, num_nodes)`` node ids."""

    type: ElementType
    ids: np.ndarray
    connectivity: np.ndarray
    locations: tuple[Location, ...] = ()


@dataclass(frozen=True, eq=False)
class Surface:
    """A ``*SURFACE``: element faces (``elements``, 1-based ``faces``) or nodes (``TYPE=NODE``)."""

    name: str
    type: str  # "ELEMENT" or "NODE"
    elements: np.ndarray
    faces: np.ndarray
    nodes: np.ndarray
    location: Location


@dataclass(frozen=True, eq=False)
class Material:
    """A ``*MATERIAL``: isotropic ``elastic = (E, nu)`` plus data a static step does not use."""

    name: str
    elastic: tuple[float, float] | None
    extra: dict[str, tuple[tuple[float | None, ...], ...]]
    location: Location


@dataclass(frozen=True, eq=False)
class SolidSection:
    """A ``*SOLID SECTION``: material of the elements of ``elset``."""

    elset: str
    material: str
    location: Location


@dataclass(frozen=True, eq=False)
class SurfaceBehavior:
    """A ``*SURFACE BEHAVIOR`` as written.

    ccx's defaults are resolved by the law (docs/method.md §4.2).

    Attributes:
        pressure_overclosure: ``EXPONENTIAL``, ``LINEAR``, ``TABULAR`` or ``HARD``.
        values: the data line (EXPONENTIAL ``(c0, p0)``; LINEAR/HARD ``(K, sigma_inf, c0)`` with
            ``None`` for missing entries, empty if no data line), empty for TABULAR.
        table: TABULAR ``(k, 2)`` rows ``(pressure, overclosure)`` (``(k, 3)`` with temperatures).
    """

    pressure_overclosure: str
    values: tuple[float | None, ...]
    table: np.ndarray | None
    location: Location


@dataclass(frozen=True, eq=False)
class Friction:
    """A ``*FRICTION`` data line: coefficient ``mu`` and stick slope (``None``: ccx default)."""

    mu: float
    stick_slope: float | None
    location: Location


@dataclass(frozen=True, eq=False)
class SurfaceInteraction:
    """A ``*SURFACE INTERACTION`` with its behavior, optional friction and unused extra data."""

    name: str
    behavior: SurfaceBehavior | None
    friction: Friction | None
    extra: dict[str, tuple[tuple[float | None, ...], ...]]
    location: Location


@dataclass(frozen=True, eq=False)
class ContactPair:
    """One data line of ``*CONTACT PAIR`` (``adjust``: a clearance, a node set name, or None)."""

    slave: str
    master: str
    interaction: str
    type: str
    small_sliding: bool
    adjust: float | str | None
    location: Location


@dataclass(frozen=True, eq=False)
class Amplitude:
    """An ``*AMPLITUDE``: piecewise linear ``values`` at ``times`` (step or total time)."""

    name: str
    times: np.ndarray
    values: np.ndarray
    total_time: bool
    location: Location


@dataclass(frozen=True, eq=False)
class Boundary:
    """One ``*BOUNDARY`` data line: dofs ``first..last`` (1..3) of ``nodes`` set to ``value``.

    ``op`` is the card's OP parameter; ccx applies it for the first card of a step only
    (``Step.boundary_op``). ``target`` is the node number or set name as written.
    """

    nodes: np.ndarray
    first_dof: int
    last_dof: int
    value: float
    amplitude: str | None
    op: str
    target: str
    location: Location


@dataclass(frozen=True, eq=False)
class Equation:
    """One ``*EQUATION``: ``sum coefficients[k] u[nodes[k], dofs[k]] = 0``, first term dependent.

    ``dofs`` are 1..3 (docs/method.md §13.1).
    """

    nodes: np.ndarray
    dofs: np.ndarray
    coefficients: np.ndarray
    location: Location


@dataclass(frozen=True, eq=False)
class CLoad:
    """One ``*CLOAD`` data line: force ``value`` in direction ``dof`` (1..3) on every node."""

    nodes: np.ndarray
    dof: int
    value: float
    amplitude: str | None
    op: str
    target: str
    location: Location


@dataclass(frozen=True, eq=False)
class DLoad:
    """One ``*DLOAD`` data line: pressure ``value`` on face ``face`` (1-based) of ``elements``."""

    elements: np.ndarray
    face: int
    value: float
    amplitude: str | None
    op: str
    target: str
    location: Location


@dataclass(frozen=True)
class Static:
    """``*STATIC`` parameters and data line (``None``: ccx default, resolved by the solver)."""

    initial_increment: float = 1.0
    period: float = 1.0
    minimum: float | None = None
    maximum: float | None = None
    direct: bool = False
    time_reset: bool = False
    total_time_at_start: float | None = None


@dataclass(frozen=True)
class Dynamic:
    """``*DYNAMIC`` (implicit) parameters; its data line (increments) is the step's ``static``."""

    alpha: float = -0.05


@dataclass(frozen=True, eq=False)
class InitialVelocity:
    """``*INITIAL CONDITIONS, TYPE=VELOCITY`` data line: ``value`` along ``dof`` of ``nodes``."""

    nodes: np.ndarray
    dof: int
    value: float
    location: Location


@dataclass(frozen=True, eq=False)
class PrintRequest:
    """A ``*NODE PRINT`` (kind ``NODE``), ``*EL PRINT`` (``EL``) or ``*CONTACT PRINT`` card.

    ``keys`` are in card order; ccx writes the blocks in that order, cards in deck order.
    ``totals`` is ``NO``, ``YES`` or ``ONLY``; ``set`` is None for contact prints.
    """

    kind: str
    keys: tuple[str, ...]
    set: str | None
    totals: str
    frequency: int | None
    location: Location


@dataclass(frozen=True, eq=False)
class FileRequest:
    """A ``*NODE/EL/CONTACT FILE`` or ``*NODE/ELEMENT/CONTACT OUTPUT`` card (``.frd`` output).

    ``kind`` is ``NODE``, ``EL`` or ``CONTACT``; ``contact_elements`` is the CONTACT ELEMENTS
    flag that asks for the ``.cel`` file (docs/method.md §8.5).
    """

    keyword: str
    kind: str
    keys: tuple[str, ...]
    set: str | None
    contact_elements: bool
    frequency: int | None
    location: Location


@dataclass(frozen=True, eq=False)
class FrictionChange:
    """``*CHANGE FRICTION`` + ``*FRICTION`` in a step (docs/method.md §11.5)."""

    interaction: str
    friction: Friction
    location: Location


@dataclass(frozen=True, eq=False)
class ModelChange:
    """``*MODEL CHANGE, TYPE=CONTACT PAIR`` data line: ``action`` is ``ADD`` or ``REMOVE``."""

    action: str
    slave: str
    master: str
    location: Location


FIELD_CONTROL_NAMES: tuple[str, ...] = (
    "R_n",
    "C_n",
    "q_0",
    "q_u",
    "R_p",
    "epsilon",
    "C_epsilon",
    "R_l",
)
"""Names of the ``*CONTROLS, PARAMETERS=FIELD`` values in data-line order (ccx manual)."""

FIELD_CONTROL_DEFAULTS: dict[str, float | None] = {
    "R_n": 0.005,
    "C_n": 0.01,
    "q_0": None,  # time average force of the previous steps, 0.01 for the first step
    "q_u": None,  # no user-defined average force
    "R_p": 0.02,
    "epsilon": 1e-5,
    "C_epsilon": 1e-3,
    "R_l": 1e-8,
}
"""Defaults of ``*CONTROLS, PARAMETERS=FIELD`` (ccx manual), by name."""


@dataclass(frozen=True, eq=False)
class Step:
    """A ``*STEP`` ... ``*END STEP`` block.

    Output requests and controls are the *effective* ones, with ccx's carry-over rules already
    applied: a step without ``*NODE PRINT`` keeps the previous step's node prints (likewise for
    ``*EL PRINT``, ``*CONTACT PRINT`` and each kind of file request); ``output_frequency`` is the
    last FREQUENCY given on any output card so far; ``controls`` maps a ``*CONTROLS`` PARAMETERS
    value to its data lines and persists until ``*CONTROLS, RESET``; ``nlgeom`` stays on once set.
    Loads and boundaries are the cards of this step only (their OP rules are the solver's job).

    Attributes:
        number: 1-based step number.
        nlgeom: geometrically nonlinear (NLGEOM).
        max_increments: INC parameter (ccx default 100).
        static: the ``*STATIC`` procedure, or the increments of the ``*DYNAMIC`` one.
        boundaries, cloads, dloads: the cards of this step, in deck order.
        prints: node, element and contact print requests in the order ccx writes them.
        file_requests: ``.frd``/``.cel`` output requests.
        output_frequency: effective FREQUENCY (write every N-th increment and the last one).
        controls: effective ``*CONTROLS`` data by PARAMETERS value (``FIELD``, ...).
        friction_changes, model_changes: ``*CHANGE FRICTION`` / ``*MODEL CHANGE`` cards.
    """

    number: int
    nlgeom: bool
    max_increments: int
    static: Static
    boundaries: tuple[Boundary, ...]
    cloads: tuple[CLoad, ...]
    dloads: tuple[DLoad, ...]
    prints: tuple[PrintRequest, ...]
    file_requests: tuple[FileRequest, ...]
    output_frequency: int
    controls: dict[str, tuple[tuple[float | None, ...], ...]]
    friction_changes: tuple[FrictionChange, ...]
    model_changes: tuple[ModelChange, ...]
    location: Location
    dynamic: Dynamic | None = None

    @property
    def node_prints(self) -> tuple[PrintRequest, ...]:
        """The ``*NODE PRINT`` requests."""
        return tuple(p for p in self.prints if p.kind == "NODE")

    @property
    def el_prints(self) -> tuple[PrintRequest, ...]:
        """The ``*EL PRINT`` requests."""
        return tuple(p for p in self.prints if p.kind == "EL")

    @property
    def contact_prints(self) -> tuple[PrintRequest, ...]:
        """The ``*CONTACT PRINT`` requests."""
        return tuple(p for p in self.prints if p.kind == "CONTACT")

    @property
    def contact_elements(self) -> bool:
        """True if a file/output request carries CONTACT ELEMENTS (write the ``.cel`` file)."""
        return any(r.contact_elements for r in self.file_requests)

    @property
    def boundary_op(self) -> str:
        """OP of the first ``*BOUNDARY`` card of the step (``MOD`` if none)."""
        return self.boundaries[0].op if self.boundaries else "MOD"

    @property
    def cload_op(self) -> str:
        """OP of the first ``*CLOAD`` card of the step (``MOD`` if none)."""
        return self.cloads[0].op if self.cloads else "MOD"

    @property
    def dload_op(self) -> str:
        """OP of the first ``*DLOAD`` card of the step (``MOD`` if none)."""
        return self.dloads[0].op if self.dloads else "MOD"

    def field_controls(self) -> dict[str, float | None]:
        """``*CONTROLS, PARAMETERS=FIELD`` values by name, ccx defaults where not given."""
        values = dict(FIELD_CONTROL_DEFAULTS)
        given = [v for line in self.controls.get("FIELD", ()) for v in line]
        for name, value in zip(FIELD_CONTROL_NAMES, given):
            if value is not None:
                values[name] = value
        return values


@dataclass(frozen=True, eq=False)
class Deck:
    """A parsed deck.

    Attributes:
        path: the main deck file.
        heading: ``*HEADING`` text.
        node_ids: ``(N,)`` node numbers, ascending.
        node_coords: ``(N, 3)`` reference coordinates, rows matching ``node_ids``.
        elements: element blocks by type name (``C3D8``, ...).
        nsets, elsets: members in definition order (duplicates kept).
        surfaces, materials, interactions, amplitudes: by upper-case name.
        sections: ``*SOLID SECTION`` cards.
        contact_pairs: in deck order (docs/method.md §2.1: contact elements follow that order).
        boundaries: ``*BOUNDARY`` cards of the model definition (before the first step).
        steps: the steps.
        ignored: ``(keyword, file, line)`` of output/control keywords that were skipped.
        warnings: every keyword and parameter skipped by ``LENIENCY``, in deck order.
        equations: ``*EQUATION`` constraints (model definition), in deck order.
    """

    path: str
    heading: str
    node_ids: np.ndarray
    node_coords: np.ndarray
    elements: dict[str, ElementBlock]
    nsets: dict[str, np.ndarray]
    elsets: dict[str, np.ndarray]
    surfaces: dict[str, Surface]
    materials: dict[str, Material]
    sections: tuple[SolidSection, ...]
    interactions: dict[str, SurfaceInteraction]
    contact_pairs: tuple[ContactPair, ...]
    amplitudes: dict[str, Amplitude]
    boundaries: tuple[Boundary, ...]
    steps: tuple[Step, ...]
    ignored: tuple[tuple[str, str, int], ...]
    warnings: tuple[DeckWarning, ...] = ()
    initial_velocities: tuple[InitialVelocity, ...] = ()
    equations: tuple[Equation, ...] = ()

    @property
    def num_elements(self) -> int:
        """Total number of elements (ccx numbers contact elements after them)."""
        return sum(int(b.ids.size) for b in self.elements.values())

    def node_index(self, ids) -> np.ndarray:
        """Row indices in ``node_ids``/``node_coords`` of node numbers ``ids`` (any shape)."""
        ids = np.asarray(ids, dtype=np.int64)
        index = np.searchsorted(self.node_ids, ids)
        index = np.minimum(index, max(self.node_ids.size - 1, 0))
        bad = self.node_ids.size == 0 or np.any(self.node_ids[index] != ids)
        if bad:
            missing = ids[self.node_ids[index] != ids] if self.node_ids.size else ids
            raise ValueError(f"node {int(missing.flat[0])} is not defined in {self.path}")
        return index

    @functools.cached_property
    def _element_lookup(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
        names = list(self.elements)
        ids = [b.ids for b in self.elements.values()]
        all_ids = np.concatenate(ids) if ids else np.zeros(0, np.int64)
        type_index = (
            np.concatenate(
                [np.full(b.ids.size, k, np.int64) for k, b in enumerate(self.elements.values())]
            )
            if ids
            else np.zeros(0, np.int64)
        )
        row = (
            np.concatenate([np.arange(b.ids.size) for b in self.elements.values()])
            if ids
            else (np.zeros(0, np.int64))
        )
        order = np.argsort(all_ids, kind="stable")
        return all_ids[order], type_index[order], row[order], names

    def element_location(self, ids) -> tuple[np.ndarray, np.ndarray]:
        """For element numbers ``ids (K,)``: index into ``list(elements)`` and row in that block."""
        ids = np.asarray(ids, dtype=np.int64).ravel()
        sorted_ids, type_index, row, _ = self._element_lookup
        pos = np.searchsorted(sorted_ids, ids)
        pos = np.minimum(pos, max(sorted_ids.size - 1, 0))
        if sorted_ids.size == 0 or np.any(sorted_ids[pos] != ids):
            missing = ids[sorted_ids[pos] != ids] if sorted_ids.size else ids
            raise ValueError(f"element {int(missing[0])} is not defined in {self.path}")
        return type_index[pos], row[pos]

    def element_types(self, ids) -> list[str]:
        """Type name of each element number in ``ids``."""
        type_index, _ = self.element_location(ids)
        names = self._element_lookup[3]
        return [names[k] for k in type_index]


# ----------------------------------------------------------------------------- surfaces, faces


def _surface(deck: Deck, surface: Surface | str) -> Surface:
    if isinstance(surface, Surface):
        return surface
    name = _name(surface)
    if name not in deck.surfaces:
        raise ValueError(f"surface {name} is not defined in {deck.path}")
    return deck.surfaces[name]


def face_nodes(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Node numbers ``(F, n)`` of the faces of an element-face surface, in CalculiX face order.

    Faces follow the surface definition order; node order is ccx's outward order (corners
    counter-clockwise seen from outside the element, then midside nodes).

    Raises:
        ValueError: nodal surface, or faces of different sizes (e.g. tets and hexes mixed).
    """
    surf = _surface(deck, surface)
    if surf.type != "ELEMENT":
        raise ValueError(
            f"surface {surf.name} ({surf.location}) is a nodal surface (TYPE=NODE): it has no "
            "faces; use node_surface_faces() for the faces ccx assigns to it"
        )
    if surf.elements.size == 0:
        return np.zeros((0, 0), dtype=np.int64)
    type_index, row = deck.element_location(surf.elements)
    blocks = list(deck.elements.values())
    sizes = {blocks[k].type.faces.shape[1] for k in np.unique(type_index)}
    if len(sizes) > 1:
        raise ValueError(
            f"surface {surf.name} ({surf.location}) mixes faces with {sorted(sizes)} nodes; "
            "split it by element type"
        )
    result = np.empty((surf.elements.size, sizes.pop()), dtype=np.int64)
    for k in np.unique(type_index):
        block = blocks[k]
        mask = type_index == k
        local = block.type.faces[surf.faces[mask] - 1]  # (m, n) element-local indices
        result[mask] = block.connectivity[row[mask][:, None], local]
    return result


def surface_nodes(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Sorted unique node numbers of a surface (its listed nodes, or all nodes of its faces)."""
    surf = _surface(deck, surface)
    if surf.type == "NODE":
        return np.unique(surf.nodes)
    return np.unique(face_nodes(deck, surf))


def external_faces(deck: Deck) -> np.ndarray:
    """Node numbers ``(F, n)`` of every face that belongs to exactly one element.

    See docs/method.md §2.1.

    Faces are in ccx outward order, grouped by element block then element then face number.

    Raises:
        ValueError: the mesh mixes face sizes (e.g. C3D4 and C3D8).
    """
    faces = []
    for block in deck.elements.values():
        if block.ids.size:
            n = block.type.faces.shape[1]
            faces.append(block.connectivity[:, block.type.faces].reshape(-1, n))
    if not faces:
        return np.zeros((0, 0), dtype=np.int64)
    if len({f.shape[1] for f in faces}) > 1:
        raise ValueError(f"{deck.path}: the mesh mixes face sizes; external faces need one type")
    all_faces = np.concatenate(faces)
    corners = 3 if all_faces.shape[1] in (3, 6) else 4
    key = np.sort(all_faces[:, :corners], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return all_faces[counts[inverse.ravel()] == 1]


def node_surface_faces(deck: Deck, surface: Surface | str) -> np.ndarray:
    """Faces ``(F, n)`` that ccx uses as slave faces of a surface (docs/method.md §2.1).

    Element-face surface: its faces. Nodal surface (``TYPE=NODE``): every external face of the
    whole mesh with at least one *corner* node in the surface.
    """
    surf = _surface(deck, surface)
    if surf.type == "ELEMENT":
        return face_nodes(deck, surf)
    faces = external_faces(deck)
    if faces.size == 0:
        return faces
    corners = 3 if faces.shape[1] in (3, 6) else 4
    return faces[np.isin(faces[:, :corners], surf.nodes).any(axis=1)]


# ----------------------------------------------------------------------------- low-level parsing


_INT_RE = re.compile(r"^[+-]?\d+$")


def _name(text: str) -> str:
    """Ccx name normalization: upper case, blanks removed."""
    return "".join(text.split()).upper()


@dataclass
class _Card:
    keyword: str  # blank-free upper-case keyword, e.g. "SOLIDSECTION"
    text: str  # keyword as written (upper-case), for messages
    params: dict[str, str | None]
    raw_params: dict[str, str | None]
    location: Location
    lines: list[tuple[list[str], str, Location]] = field(default_factory=list)

    @property
    def name(self) -> str:
        return _CANONICAL.get(self.keyword, self.text)


def _split_keyword_line(text: str, location: Location) -> _Card:
    fields = text[1:].split(",")
    keyword_text = fields[0].strip().upper()
    params: dict[str, str | None] = {}
    raw: dict[str, str | None] = {}
    for item in fields[1:]:
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        key = _name(key)
        params[key] = _name(value) if sep else None
        raw[key] = value.strip() if sep else None
    return _Card(_name(keyword_text), keyword_text, params, raw, location)


def _data_fields(text: str) -> list[str]:
    fields = _name(text).split(",")
    if fields and fields[-1] == "":
        fields.pop()
    return fields


# Canonical spelling of every keyword mentioned in messages, by blank-free form.
_KEYWORDS = """
AMPLITUDE; BEAM GENERAL SECTION; BEAM SECTION; BOUNDARY; BOUNDARYF; BUCKLE; CFD; CFLUX;
CHANGE FRICTION; CHANGE MATERIAL; CHANGE PLASTIC; CHANGE SURFACE BEHAVIOR; CHANGE SOLID SECTION;
CLEARANCE; CLOAD; COMPLEX FREQUENCY; CONDUCTIVITY; CONTACT DAMPING; CONTACT FILE; CONTACT OUTPUT;
CONTACT PAIR; CONTACT PRINT; CONTROLS; COUPLED TEMPERATURE-DISPLACEMENT; COUPLING; CREEP;
CYCLIC HARDENING; CYCLIC SYMMETRY MODEL; DAMPING; DASHPOT; DEFORMATION PLASTICITY; DENSITY;
DEPVAR; DESIGNVARIABLES; DFLUX; DISTRIBUTING; DISTRIBUTING COUPLING; DLOAD; DSLOAD; DYNAMIC;
ELASTIC; ELECTRICAL CONDUCTIVITY; ELECTROMAGNETICS; ELEMENT; ELEMENT OUTPUT; EL FILE; EL PRINT;
ELSET; END STEP; EQUATION; EXPANSION; FACE PRINT; FILM; FLUID CONSTANTS; FLUID SECTION;
FREQUENCY; FRICTION; GAP; GAP CONDUCTANCE; GAP HEAT GENERATION; GREEN; HEADING; HEAT TRANSFER;
HYPERELASTIC; HYPERFOAM; INCLUDE; INITIAL CONDITIONS; INITIAL STRAIN INCREASE; KINEMATIC;
MAGNETIC PERMEABILITY; MASS; MASS FLOW; MATERIAL; MEMBRANE SECTION; MODAL DAMPING; MODAL DYNAMIC;
MODEL CHANGE; MPC; NETWORK MPC; NO ANALYSIS; NODAL THICKNESS; NODE; NODE FILE; NODE OUTPUT;
NODE PRINT; NORMAL; NSET; OBJECTIVE; ORIENTATION; OUTPUT; PHYSICAL CONSTANTS; PLASTIC; PREPRINT;
PRE-TENSION SECTION; RADIATE; REFINE MESH; RESTART; RETAINED NODAL DOFS; RIGID BODY;
SECTION PRINT; SELECT CYCLIC SYMMETRY MODES; SENSITIVITY; SHELL SECTION; SOLID SECTION;
SPECIFIC GAS CONSTANT; SPECIFIC HEAT; SPRING; STATIC; STEADY STATE DYNAMICS; STEP; SUBMODEL;
SUBSTRUCTURE GENERATE; SUBSTRUCTURE MATRIX OUTPUT; SURFACE; SURFACE BEHAVIOR;
SURFACE INTERACTION; TEMPERATURE; TIE; TIME POINTS; TRANSFORM; TRANSFORMF; UNCOUPLED
TEMPERATURE-DISPLACEMENT; USER ELEMENT; USER MATERIAL; USER SECTION; VALUES AT INFINITY;
VIEWFACTOR; VISCO; CONSTRAINT; FILTER; GEOMETRIC CONSTRAINT; ROBUSTDESIGN; CRACK PROPAGATION;
CHANGE CONTACT TYPE; CHANGE KINEMATIC; CHANGE TIE; ELECTROMAGNETICS; EMODAL DAMPING
"""
_CANONICAL: dict[str, str] = {
    _name(k): "*" + " ".join(k.split())
    for k in _KEYWORDS.replace("\n", " ").split(";")
    if k.strip()
}

# Constraints and kinematic couplings: "not supported yet".
_UNSUPPORTED_CONSTRAINTS = {
    _name(k)
    for k in (
        "TIE", "RIGID BODY", "MPC", "NETWORK MPC", "COUPLING", "KINEMATIC",
        "DISTRIBUTING", "DISTRIBUTING COUPLING", "PRE-TENSION SECTION", "CLEARANCE", "GAP",
        "SPRING", "DASHPOT", "MASS", "TRANSFORM", "ORIENTATION", "CHANGE CONTACT TYPE",
        "CHANGE KINEMATIC", "CHANGE TIE", "CYCLIC SYMMETRY MODEL", "RETAINED NODAL DOFS",
    )
}  # fmt: skip

# What the reader does with the keywords and parameters it does not use. ccx 2.20 prints a warning
# for every keyword and parameter it does not recognize and goes on; here a skipped keyword or
# parameter must also be one that cannot change the solution, the others are refused:
#   keyword -> {parameter: (action, reason)}, action "warn" (one DeckWarning, the card is read
#   without it) or "refuse" (DeckError); parameter "" is the whole keyword, "*" any parameter.
# Keywords and parameters in neither this table nor a handler are refused as well.
_OUTPUT_ONLY = "output only: ccx 2.20 ignores it"
_TIME_POINTS = "ccx cuts the increments to reach the time points"
_FILE_RULES = {"POSITION": ("warn", _OUTPUT_ONLY), "TIME POINTS": ("refuse", _TIME_POINTS)}
LENIENCY: dict[str, dict[str, tuple[str, str]]] = {
    "*HEADING": {"*": ("warn", "ccx ignores *HEADING parameters")},
    "*NSET": {"FREQUENCY": ("warn", "not a *NSET parameter: ccx ignores it")},
    "*ELSET": {"FREQUENCY": ("warn", "not a *ELSET parameter: ccx ignores it")},
    "*NODE FILE": _FILE_RULES,
    "*EL FILE": _FILE_RULES,
    "*CONTACT FILE": _FILE_RULES,
    "*NODE OUTPUT": _FILE_RULES,
    "*ELEMENT OUTPUT": _FILE_RULES,
    "*CONTACT OUTPUT": _FILE_RULES,
    "*NODE PRINT": {"TIME POINTS": ("refuse", _TIME_POINTS)},
    "*EL PRINT": {"TIME POINTS": ("refuse", _TIME_POINTS)},
    "*CONTACT PRINT": {"TIME POINTS": ("refuse", _TIME_POINTS)},
    "*OUTPUT": {"": ("warn", "output database only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*FACE PRINT": {"": ("warn", "output only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*SECTION PRINT": {"": ("warn", "output only"), "TIME POINTS": ("refuse", _TIME_POINTS)},
    "*TIME POINTS": {"": ("warn", "used only by output requests with TIME POINTS")},
    "*PREPRINT": {"": ("warn", "Abaqus printout control: ccx ignores it")},
    "*RESTART": {
        "": ("warn", "restart files are not written"),
        "READ": ("refuse", "starts from the state of an earlier run"),
    },
    "*SOLID SECTION": {"ORIENTATION": ("refuse", "turns the material axes")},
    "*BOUNDARY": {
        "FIXED": ("refuse", "holds the displacement of the previous step"),
        "USER": ("refuse", "values from a user subroutine"),
        "SUBMODEL": ("refuse", "values from a global model"),
    },
    "*STEP": {"AMPLITUDE": ("refuse", "ramps or steps the loads")},
}
_LENIENCY = {
    _name(k[1:]): {_name(p) if p not in ("", "*") else p: (a, r, p) for p, (a, r) in rules.items()}
    for k, rules in LENIENCY.items()
}

# Skipped output keywords whose FREQUENCY still sets the frequency of every output (ccx rule).
_SETS_FREQUENCY = {"OUTPUT", "FACEPRINT", "SECTIONPRINT"}

# Material data a static step does not use.
_UNUSED_MATERIAL = {_name(k) for k in ("DENSITY", "EXPANSION", "CONDUCTIVITY", "SPECIFIC HEAT")}

# Interaction data a static mechanical step does not use.
_UNUSED_INTERACTION = {_name(k) for k in ("CONTACT DAMPING", "GAP CONDUCTANCE")}

# Keywords that continue the current *MATERIAL / *SURFACE INTERACTION block.
_CONTEXT_KEYWORDS = (
    {"ELASTIC", "FRICTION", "SURFACEBEHAVIOR"} | _UNUSED_MATERIAL | _UNUSED_INTERACTION
)

_STEP_KEYWORDS = {
    _name(k)
    for k in (
        "STATIC", "CLOAD", "DLOAD", "NODE PRINT", "EL PRINT", "CONTACT PRINT", "NODE FILE",
        "EL FILE", "CONTACT FILE", "NODE OUTPUT", "ELEMENT OUTPUT", "CONTACT OUTPUT", "CONTROLS",
        "CHANGE FRICTION", "MODEL CHANGE", "END STEP", "DYNAMIC",
    )
}  # fmt: skip

_MODEL_KEYWORDS = {
    _name(k)
    for k in (
        "NODE", "ELEMENT", "NSET", "ELSET", "SURFACE", "MATERIAL", "ELASTIC", "SOLID SECTION",
        "CONTACT PAIR", "SURFACE INTERACTION", "SURFACE BEHAVIOR", "DENSITY", "EXPANSION",
        "CONDUCTIVITY", "SPECIFIC HEAT", "CONTACT DAMPING", "GAP CONDUCTANCE", "EQUATION",
        "INITIAL CONDITIONS",
    )
}  # fmt: skip

_FILE_KEYWORDS = {
    "NODEFILE": "NODE",
    "NODEOUTPUT": "NODE",
    "ELFILE": "EL",
    "ELEMENTOUTPUT": "EL",
    "CONTACTFILE": "CONTACT",
    "CONTACTOUTPUT": "CONTACT",
}

_PRINT_KEYS = {"NODE": ("U", "RF"), "EL": ("S",), "CONTACT": ("CDIS", "CSTR", "CELS", "CNUM")}


# ----------------------------------------------------------------------------- the reader


@dataclass
class _StepBuilder:
    number: int
    nlgeom: bool
    max_increments: int
    location: Location
    static: Static | None = None
    dynamic: Dynamic | None = None
    boundaries: list[Boundary] = field(default_factory=list)
    cloads: list[CLoad] = field(default_factory=list)
    dloads: list[DLoad] = field(default_factory=list)
    new_prints: list[PrintRequest] = field(default_factory=list)
    new_files: list[FileRequest] = field(default_factory=list)
    friction_changes: list[FrictionChange] = field(default_factory=list)
    model_changes: list[ModelChange] = field(default_factory=list)
    pending_friction: tuple[str, Location] | None = None


@dataclass
class _MaterialBuilder:
    name: str
    location: Location
    elastic: tuple[float, float] | None = None
    elastic_location: Location | None = None
    extra: dict[str, tuple[tuple[float | None, ...], ...]] = field(default_factory=dict)


@dataclass
class _InteractionBuilder:
    name: str
    location: Location
    behavior: SurfaceBehavior | None = None
    friction: Friction | None = None
    extra: dict[str, tuple[tuple[float | None, ...], ...]] = field(default_factory=dict)


class _Reader:
    """Keyword-by-keyword deck reader; one method ``_k_<KEYWORD>`` per supported keyword."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.heading: list[str] = []
        self.node_ids: list[int] = []
        self.node_coords: list[tuple[float, float, float]] = []
        self.node_locs: list[Location] = []
        self.element_rows: dict[str, list[list[int]]] = {t: [] for t in ELEMENT_TYPES}
        self.element_ids: dict[str, list[int]] = {t: [] for t in ELEMENT_TYPES}
        self.element_locs: dict[str, list[Location]] = {t: [] for t in ELEMENT_TYPES}
        self.nsets: dict[str, list[int]] = {}
        self.elsets: dict[str, list[int]] = {}
        self.set_locations: dict[tuple[str, str], Location] = {}
        self.surfaces: dict[str, Surface] = {}
        self.materials: dict[str, _MaterialBuilder] = {}
        self.sections: list[SolidSection] = []
        self.interactions: dict[str, _InteractionBuilder] = {}
        self.contact_pairs: list[ContactPair] = []
        self.amplitudes: dict[str, Amplitude] = {}
        self.boundaries: list[Boundary] = []
        self.initial_velocities: list[InitialVelocity] = []
        self.equations: list[Equation] = []
        self.steps: list[Step] = []
        self.ignored: list[tuple[str, str, int]] = []
        self.warnings: list[DeckWarning] = []
        self.step: _StepBuilder | None = None
        self.context: _MaterialBuilder | _InteractionBuilder | None = None
        # carried over between steps
        self.prints: list[PrintRequest] = []
        self.files: list[FileRequest] = []
        self.controls: dict[str, tuple[tuple[float | None, ...], ...]] = {}
        self.frequency = 1
        self.nlgeom = False
        # checks done once everything is read: (what, ids, location)
        self.node_refs: list[tuple[str, np.ndarray, Location]] = []
        self.element_refs: list[tuple[str, np.ndarray, Location]] = []

    # -- input ----------------------------------------------------------------------------------

    def _lines(
        self, path: Path, include_loc: Location | None, stack: tuple[Path, ...]
    ) -> Iterator[tuple[str, Location]]:
        resolved = path.resolve()
        if resolved in stack:
            raise DeckError(f"*INCLUDE of {path} is recursive", include_loc)
        try:
            text = path.read_text(encoding="latin-1")
        except OSError as exc:
            where = "deck" if include_loc is None else "*INCLUDE file"
            raise DeckError(f"cannot read {where} {path}: {exc.strerror}", include_loc) from None
        for number, line in enumerate(text.splitlines(), start=1):
            location = Location(str(path), number)
            stripped = line.strip()
            if stripped.startswith("*") and not stripped.startswith("**"):
                card = _split_keyword_line(stripped, location)
                if card.keyword == "INCLUDE":
                    included = self._include_path(card, path)
                    yield from self._lines(included, location, (*stack, resolved))
                    continue
            yield line, location

    def _include_path(self, card: _Card, current: Path) -> Path:
        self._check_params(card, allowed={"INPUT"}, required={"INPUT"})
        name = (card.raw_params["INPUT"] or "").strip().strip('"')
        if not name:
            raise DeckError("*INCLUDE needs INPUT=<file>", card.location)
        candidate = Path(name)
        if not candidate.is_absolute():
            for base in (current.parent, self.path.parent):
                if (base / candidate).exists():
                    return base / candidate
            return current.parent / candidate
        return candidate

    def _cards(self) -> Iterator[_Card]:
        card: _Card | None = None
        for line, location in self._lines(self.path, None, ()):
            stripped = line.strip()
            if not stripped or stripped.startswith("**"):
                continue
            if stripped.startswith("*"):
                if card is not None:
                    yield card
                card = _split_keyword_line(stripped, location)
            elif card is None:
                raise DeckError("data line before the first keyword", location)
            else:
                card.lines.append((_data_fields(stripped), line, location))
        if card is not None:
            yield card

    # -- helpers --------------------------------------------------------------------------------

    @staticmethod
    def _check_params(card: _Card, allowed: set[str], required: set[str] = frozenset()) -> None:
        for key in card.params:
            if key not in allowed:
                raise DeckError(f"parameter {key} of {card.name} is not supported", card.location)
        for key in required:
            if key not in card.params or card.params[key] in (None, ""):
                raise DeckError(f"{card.name} needs the parameter {key}=...", card.location)

    @staticmethod
    def _no_data(card: _Card) -> None:
        if card.lines:
            raise DeckError(f"{card.name} takes no data lines", card.lines[0][2])

    @staticmethod
    def _need_data(card: _Card) -> None:
        if not card.lines:
            raise DeckError(f"{card.name} needs a data line", card.location)

    @staticmethod
    def _new_name(card: _Card, defined: dict, what: str) -> str:
        """The NAME parameter of ``card``, which must not name an already defined ``what``."""
        name = card.params["NAME"] or ""
        if name in defined:
            raise DeckError(
                f"{what} {name} is defined twice (first at {defined[name].location})", card.location
            )
        return name

    @staticmethod
    def _int(token: str, what: str, location: Location) -> int:
        if token.isascii() and token.isdigit():
            return int(token)
        if not _INT_RE.match(token):
            raise DeckError(f"bad {what} {token!r}: an integer is required", location)
        return int(token)

    @staticmethod
    def _float(token: str, what: str, location: Location) -> float:
        try:
            value = float(token.replace("D", "E").replace("d", "e"))
        except ValueError:
            raise DeckError(f"bad number {token!r} for {what}", location) from None
        if not np.isfinite(value):
            raise DeckError(f"bad number {token!r} for {what}: not finite", location)
        return value

    def _optional_float(self, fields: list[str], i: int, what: str, loc: Location) -> float | None:
        if i < len(fields) and fields[i] != "":
            return self._float(fields[i], what, loc)
        return None

    def _floats_line(self, fields: list[str], what: str, loc: Location) -> tuple[float | None, ...]:
        return tuple(self._optional_float(fields, i, what, loc) for i in range(len(fields)))

    def _nodes_of(self, token: str, card: _Card, loc: Location) -> np.ndarray:
        if _INT_RE.match(token):
            ids = np.array([int(token)], dtype=np.int64)
            self.node_refs.append((f"{card.name}", ids, loc))
            return ids
        if token not in self.nsets:
            raise DeckError(f"node set {token} is not defined (before this line)", loc)
        return np.array(self.nsets[token], dtype=np.int64)

    def _elements_of(self, token: str, card: _Card, loc: Location) -> np.ndarray:
        if _INT_RE.match(token):
            return np.array([int(token)], dtype=np.int64)
        if token not in self.elsets:
            raise DeckError(f"element set {token} is not defined (before this line)", loc)
        return np.array(self.elsets[token], dtype=np.int64)

    def _dof(self, token: str, loc: Location) -> int:
        dof = self._int(token, "degree of freedom", loc)
        if dof not in (1, 2, 3):
            raise DeckError(
                f"degree of freedom {dof} is not supported (solid elements have dofs 1, 2, 3)", loc
            )
        return dof

    def _op(self, card: _Card) -> str:
        op = card.params.get("OP") or "MOD"
        if op not in ("NEW", "MOD"):
            raise DeckError(f"OP={op} of {card.name}: use OP=NEW or OP=MOD", card.location)
        return op

    def _frequency(self, card: _Card) -> int | None:
        if "FREQUENCY" not in card.params:
            return None
        value = self._int(card.params["FREQUENCY"] or "", "FREQUENCY", card.location)
        if value < 0:
            raise DeckError(f"FREQUENCY must be >= 0, got {value}", card.location)
        self.frequency = value
        return value

    def _in_step(self, card: _Card) -> _StepBuilder:
        if self.step is None:
            raise DeckError(f"{card.name} is a step keyword: it must follow *STEP", card.location)
        return self.step

    # -- main loop ------------------------------------------------------------------------------

    def read(self) -> Deck:
        for card in self._cards():
            self._dispatch(card)
        if self.step is not None:
            raise DeckError("*STEP without *END STEP", self.step.location)
        return self._finish()

    def _dispatch(self, card: _Card) -> None:
        key = card.keyword
        if key in _STEP_KEYWORDS and key != "ENDSTEP":
            self._in_step(card)
        if key in _MODEL_KEYWORDS and self.step is not None:
            raise DeckError(
                f"{card.name} is a model definition keyword: it must come before the first *STEP",
                card.location,
            )
        if key not in _CONTEXT_KEYWORDS:
            self.context = None
        if self._apply_leniency(card):
            return
        handler: Callable[[_Card], None] | None = getattr(self, f"_k_{key.replace('-', '_')}", None)
        if handler is not None:
            handler(card)
        elif key in _UNUSED_MATERIAL:
            self._unused_material(card)
        elif key in _UNUSED_INTERACTION:
            self._unused_interaction(card)
        elif key in _UNSUPPORTED_CONSTRAINTS:
            raise DeckError(f"{card.name} is not supported yet (constraint)", card.location)
        elif key in _CANONICAL:
            raise DeckError(f"{card.name} is not supported yet", card.location)
        else:
            raise DeckError(f"unknown keyword *{card.text}", card.location)

    def _apply_leniency(self, card: _Card) -> bool:
        """Apply ``LENIENCY`` to ``card``: warn or refuse; True if the whole card is skipped."""
        rules = _LENIENCY.get(card.keyword, {})
        for key in list(card.params):
            rule = rules.get(key) or rules.get("*")
            if rule is None:
                continue
            action, reason, spelling = rule
            if action == "refuse":
                raise DeckError(
                    f"{card.name}, {spelling} is not supported yet ({reason})", card.location
                )
            raw = card.raw_params[key]
            written = key if spelling == "*" else spelling
            self.warnings.append(DeckWarning(
                card.name, written if raw is None else f"{written}={raw}", reason, card.location
            ))  # fmt: skip
            del card.params[key], card.raw_params[key]
        if "" not in rules:
            return False
        self._ignore(card, rules[""][1])
        return True

    # -- model definition -----------------------------------------------------------------------

    def _k_HEADING(self, card: _Card) -> None:
        self._check_params(card, allowed=set())
        self.heading.extend(raw.strip() for _, raw, _ in card.lines)

    def _k_NODE(self, card: _Card) -> None:
        self._check_params(card, allowed={"NSET"})
        ids: list[int] = []
        for fields, _, loc in card.lines:
            if not 1 <= len(fields) <= 4:
                raise DeckError("*NODE data line: node number, x, y, z", loc)
            ids.append(self._int(fields[0], "node number", loc))
            xyz = [self._optional_float(fields, i, "a coordinate", loc) or 0.0 for i in (1, 2, 3)]
            self.node_coords.append((xyz[0], xyz[1], xyz[2]))
            self.node_locs.append(loc)
        self.node_ids.extend(ids)
        if card.params.get("NSET"):
            self._add_set(self.nsets, "node", card.params["NSET"], ids, card.location)

    def _k_ELEMENT(self, card: _Card) -> None:
        self._check_params(card, allowed={"TYPE", "ELSET"}, required={"TYPE"})
        type_name = card.params["TYPE"] or ""
        if type_name not in ELEMENT_TYPES:
            supported = ", ".join(ELEMENT_TYPES)
            why = _REFUSED_ELEMENTS.get(type_name, "")
            raise DeckError(
                f"element type {type_name} is not supported{why} (supported: {supported})",
                card.location,
            )
        etype = ELEMENT_TYPES[type_name]
        needed = etype.num_nodes + 1
        ids: list[int] = []
        tokens: list[str] = []
        start: Location | None = None
        for fields, raw, loc in card.lines:
            if not tokens:
                start = loc
            tokens.extend(fields)
            if len(tokens) < needed:
                continue
            if len(tokens) > needed:
                raise DeckError(
                    f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has "
                    f"{etype.num_nodes}",
                    start,
                )
            numbers = [self._int(t, "element or node number", start) for t in tokens]
            ids.append(numbers[0])
            self.element_rows[type_name].append(numbers[1:])
            self.element_locs[type_name].append(start)
            tokens = []
        if tokens:
            raise DeckError(
                f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has "
                f"{etype.num_nodes}",
                start,
            )
        self.element_ids[type_name].extend(ids)
        if card.params.get("ELSET"):
            self._add_set(self.elsets, "element", card.params["ELSET"], ids, card.location)

    def _add_set(self, sets: dict, kind: str, name: str, ids: list[int], loc: Location) -> None:
        sets.setdefault(name, []).extend(ids)
        self.set_locations.setdefault((kind, name), loc)

    def _k_NSET(self, card: _Card) -> None:
        self._set_card(card, "NSET", self.nsets, "node")

    def _k_ELSET(self, card: _Card) -> None:
        self._set_card(card, "ELSET", self.elsets, "element")

    def _set_card(self, card: _Card, param: str, sets: dict, kind: str) -> None:
        self._check_params(card, allowed={param, "GENERATE"}, required={param})
        name = card.params[param] or ""
        members: list[int] = []
        for fields, _, loc in card.lines:
            if "GENERATE" in card.params:
                if len(fields) not in (2, 3):
                    raise DeckError(
                        f"{card.name}, GENERATE data line: first, last[, increment]", loc
                    )
                first, last = (self._int(t, f"{kind} number", loc) for t in fields[:2])
                inc = self._int(fields[2], "increment", loc) if len(fields) == 3 else 1
                if inc <= 0 or last < first:
                    raise DeckError(
                        f"{card.name}, GENERATE: need first <= last and increment > 0, got "
                        f"{first}, {last}, {inc}",
                        loc,
                    )
                ids = list(range(first, last + 1, inc))
                self._ref(kind, card, np.array(ids, dtype=np.int64), loc)
                members.extend(ids)
                continue
            for token in fields:
                if token == "":
                    continue
                if _INT_RE.match(token):
                    self._ref(kind, card, np.array([int(token)], dtype=np.int64), loc)
                    members.append(int(token))
                elif token in sets:
                    members.extend(sets[token])
                else:
                    raise DeckError(f"{kind} set {token} is not defined (before this line)", loc)
        self._add_set(sets, kind, name, members, card.location)

    def _ref(self, kind: str, card: _Card, ids: np.ndarray, loc: Location) -> None:
        (self.node_refs if kind == "node" else self.element_refs).append((card.name, ids, loc))

    def _k_SURFACE(self, card: _Card) -> None:
        self._check_params(card, allowed={"NAME", "TYPE"}, required={"NAME"})
        stype = card.params.get("TYPE") or "ELEMENT"
        if stype not in ("ELEMENT", "NODE"):
            raise DeckError(f"*SURFACE TYPE={stype}: use TYPE=ELEMENT or TYPE=NODE", card.location)
        name = self._new_name(card, self.surfaces, "surface")
        elements: list[np.ndarray] = []
        faces: list[np.ndarray] = []
        nodes: list[np.ndarray] = []
        for fields, _, loc in card.lines:
            fields = [f for f in fields if f != ""]
            if stype == "NODE":
                for token in fields:
                    nodes.append(self._nodes_of(token, card, loc))
                continue
            if len(fields) != 2:
                raise DeckError(
                    "*SURFACE data line: element or element set, face label S1..S6", loc
                )
            label = fields[1]
            if not re.fullmatch(r"S[1-6]", label):
                raise DeckError(f"bad face label {label!r}: use S1..S6", loc)
            ids = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", ids, loc))
            elements.append(ids)
            faces.append(np.full(ids.size, int(label[1]), dtype=np.int64))
        self.surfaces[name] = Surface(
            name=name,
            type=stype,
            elements=_frozen_array(np.concatenate(elements) if elements else [], np.int64),
            faces=_frozen_array(np.concatenate(faces) if faces else [], np.int64),
            nodes=_frozen_array(np.concatenate(nodes) if nodes else [], np.int64),
            location=card.location,
        )

    def _k_MATERIAL(self, card: _Card) -> None:
        self._check_params(card, allowed={"NAME"}, required={"NAME"})
        self._no_data(card)
        name = self._new_name(card, self.materials, "material")
        self.context = self.materials[name] = _MaterialBuilder(name, card.location)

    def _material(self, card: _Card) -> _MaterialBuilder:
        if not isinstance(self.context, _MaterialBuilder):
            raise DeckError(f"{card.name} must follow a *MATERIAL card", card.location)
        return self.context

    def _k_ELASTIC(self, card: _Card) -> None:
        material = self._material(card)
        self._check_params(card, allowed={"TYPE"})
        etype = card.params.get("TYPE") or "ISO"
        if etype != "ISO":
            raise DeckError(
                f"*ELASTIC, TYPE={etype} is not supported yet (only isotropic)", card.location
            )
        self._need_data(card)
        if len(card.lines) > 1:
            raise DeckError(
                "temperature-dependent *ELASTIC (several data lines) is not supported yet",
                card.lines[1][2],
            )
        fields, _, loc = card.lines[0]
        if not 2 <= len(fields) <= 3:
            raise DeckError("*ELASTIC data line: E, nu[, temperature]", loc)
        young = self._float(fields[0], "Young's modulus", loc)
        nu = self._float(fields[1], "Poisson's ratio", loc)
        if young <= 0.0 or not -1.0 < nu < 0.5:
            raise DeckError(f"*ELASTIC needs E > 0 and -1 < nu < 0.5, got {young}, {nu}", loc)
        if material.elastic is not None:
            raise DeckError(
                f"material {material.name} has two *ELASTIC cards (first at "
                f"{material.elastic_location})",
                card.location,
            )
        material.elastic = (young, nu)
        material.elastic_location = card.location

    def _unused_material(self, card: _Card) -> None:
        material = self._material(card)
        material.extra[card.name] = tuple(
            self._floats_line(f, card.name, loc) for f, _, loc in card.lines
        )

    def _k_SOLIDSECTION(self, card: _Card) -> None:
        self._check_params(card, allowed={"ELSET", "MATERIAL"}, required={"ELSET", "MATERIAL"})
        elset = card.params["ELSET"] or ""
        if elset not in self.elsets:
            raise DeckError(f"element set {elset} is not defined (before this line)", card.location)
        self.sections.append(SolidSection(elset, card.params["MATERIAL"] or "", card.location))

    def _k_SURFACEINTERACTION(self, card: _Card) -> None:
        self._check_params(card, allowed={"NAME"}, required={"NAME"})
        self._no_data(card)
        name = self._new_name(card, self.interactions, "surface interaction")
        self.context = self.interactions[name] = _InteractionBuilder(name, card.location)

    def _interaction(self, card: _Card) -> _InteractionBuilder:
        if not isinstance(self.context, _InteractionBuilder):
            raise DeckError(f"{card.name} must follow a *SURFACE INTERACTION card", card.location)
        return self.context

    def _k_SURFACEBEHAVIOR(self, card: _Card) -> None:
        interaction = self._interaction(card)
        key = "PRESSURE-OVERCLOSURE"
        self._check_params(card, allowed={key}, required={key})
        law = card.params["PRESSURE-OVERCLOSURE"] or ""
        what = f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE={law}"
        values: tuple[float | None, ...] = ()
        table = None
        if law == "EXPONENTIAL":
            self._need_data(card)
            fields, _, loc = card.lines[0]
            if len(card.lines) != 1 or len(fields) != 2:
                raise DeckError(f"{what}: one data line c0, p0", loc)
            c0, p0 = (self._float(t, "c0/p0", loc) for t in fields)
            if c0 <= 0.0 or p0 < 0.0:
                raise DeckError(f"{what} needs c0 > 0 and p0 >= 0, got {c0}, {p0}", loc)
            values = (c0, p0)
        elif law in ("LINEAR", "HARD"):
            if len(card.lines) > 1:
                raise DeckError(f"{what}: at most one data line K, sigma_inf, c0", card.lines[1][2])
            if card.lines:
                fields, _, loc = card.lines[0]
                if len(fields) > 3:
                    raise DeckError(f"{what}: data line K, sigma_inf, c0", loc)
                values = self._floats_line(fields, "K/sigma_inf/c0", loc)
        elif law == "TABULAR":
            self._need_data(card)
            rows = []
            for fields, _, loc in card.lines:
                if len(fields) not in (2, 3):
                    raise DeckError(f"{what}: data lines pressure, overclosure[, temperature]", loc)
                rows.append([self._float(t, "pressure/overclosure", loc) for t in fields])
            if len({len(r) for r in rows}) > 1:
                raise DeckError(f"{what}: give temperatures on all lines or none", card.location)
            table = _frozen_array(rows, np.float64)
        elif law == "TIED":
            raise DeckError(f"{what} is for face-to-face contact: not supported", card.location)
        else:
            raise DeckError(f"{what}: use EXPONENTIAL, LINEAR, TABULAR or HARD", card.location)
        if interaction.behavior is not None:
            raise DeckError(
                f"surface interaction {interaction.name} has two *SURFACE BEHAVIOR cards",
                card.location,
            )
        interaction.behavior = SurfaceBehavior(law, values, table, card.location)

    def _friction_data(self, card: _Card) -> Friction:
        self._check_params(card, allowed=set())
        self._need_data(card)
        fields, _, loc = card.lines[-1]  # several lines: the last one counts (as in ccx)
        if not 1 <= len(fields) <= 2:
            raise DeckError("*FRICTION data line: mu[, stick slope]", loc)
        mu = self._float(fields[0], "friction coefficient", loc)
        if mu <= 0.0:
            raise DeckError(f"*FRICTION needs a friction coefficient > 0, got {mu}", loc)
        return Friction(mu, self._optional_float(fields, 1, "stick slope", loc), card.location)

    def _k_FRICTION(self, card: _Card) -> None:
        if self.step is not None:
            if self.step.pending_friction is None:
                raise DeckError("*FRICTION in a step must follow *CHANGE FRICTION", card.location)
            name, loc = self.step.pending_friction
            self.step.friction_changes.append(FrictionChange(name, self._friction_data(card), loc))
            self.step.pending_friction = None
            return
        interaction = self._interaction(card)
        interaction.friction = self._friction_data(card)

    def _unused_interaction(self, card: _Card) -> None:
        interaction = self._interaction(card)
        interaction.extra[card.name] = tuple(
            self._floats_line(f, card.name, loc) for f, _, loc in card.lines
        )

    def _k_CONTACTPAIR(self, card: _Card) -> None:
        self._check_params(card, allowed={"INTERACTION", "TYPE", "SMALLSLIDING", "ADJUST"},
                           required={"INTERACTION", "TYPE"})  # fmt: skip
        ctype = card.params["TYPE"] or ""
        if ctype != "NODETOSURFACE":
            raise DeckError(
                f"*CONTACT PAIR, TYPE={card.raw_params['TYPE']} is not supported yet "
                "(only TYPE=NODE TO SURFACE)",
                card.location,
            )
        if card.params.get("SMALLSLIDING") is not None:
            raise DeckError("SMALL SLIDING takes no value", card.location)
        adjust: float | str | None = None
        if "ADJUST" in card.params:
            token = card.params["ADJUST"] or ""
            if not token:
                raise DeckError(
                    "ADJUST needs a value: a clearance >= 0 or a node set", card.location
                )
            if token in self.nsets:
                adjust = token
            else:
                try:
                    adjust = float(re.sub(r"[dD]", "e", token))
                except ValueError:
                    raise DeckError(
                        f"ADJUST={token}: neither a number nor a defined node set", card.location
                    ) from None
                if not adjust >= 0.0:
                    raise DeckError(f"ADJUST={token} must be >= 0", card.location)
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 2 or "" in fields:
                raise DeckError("*CONTACT PAIR data line: slave surface, master surface", loc)
            self.contact_pairs.append(
                ContactPair(
                    slave=fields[0],
                    master=fields[1],
                    interaction=card.params["INTERACTION"] or "",
                    type="NODE TO SURFACE",
                    small_sliding="SMALLSLIDING" in card.params,
                    adjust=adjust,
                    location=loc,
                )
            )

    def _k_AMPLITUDE(self, card: _Card) -> None:
        self._check_params(card, allowed={"NAME", "TIME"}, required={"NAME"})
        time = card.params.get("TIME")
        if time not in (None, "TOTALTIME", "STEPTIME"):
            raise DeckError(f"*AMPLITUDE, TIME={time}: use TIME=TOTAL TIME", card.location)
        self._need_data(card)
        values: list[float] = []
        for fields, _, loc in card.lines:
            values.extend(self._float(t, "amplitude data", loc) for t in fields if t != "")
        if len(values) % 2:
            raise DeckError(
                "*AMPLITUDE needs time, value pairs (odd number of entries)", card.location
            )
        pairs = np.array(values, dtype=np.float64).reshape(-1, 2)
        if np.any(np.diff(pairs[:, 0]) < 0.0):
            raise DeckError("*AMPLITUDE times must not decrease", card.location)
        name = card.params["NAME"] or ""
        self.amplitudes[name] = Amplitude(
            name,
            _frozen_array(pairs[:, 0], np.float64),
            _frozen_array(pairs[:, 1], np.float64),
            time == "TOTALTIME",
            card.location,
        )

    def _amplitude_param(self, card: _Card) -> str | None:
        name = card.params.get("AMPLITUDE")
        if name is not None and name not in self.amplitudes:
            raise DeckError(f"amplitude {name} is not defined (before this line)", card.location)
        return name

    def _k_BOUNDARY(self, card: _Card) -> None:
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op = self._op(card)
        amplitude = self._amplitude_param(card)
        target_list = self.step.boundaries if self.step is not None else self.boundaries
        for fields, _, loc in card.lines:
            if not 2 <= len(fields) <= 4:
                raise DeckError(
                    "*BOUNDARY data line: node or node set, first dof[, last dof[, value]]", loc
                )
            nodes = self._nodes_of(fields[0], card, loc)
            first = self._dof(fields[1], loc)
            last = self._dof(fields[2], loc) if len(fields) > 2 and fields[2] else first
            if last < first:
                raise DeckError(f"*BOUNDARY: last dof {last} < first dof {first}", loc)
            value = self._optional_float(fields, 3, "prescribed value", loc) or 0.0
            target_list.append(
                Boundary(
                    _frozen_array(nodes, np.int64),
                    first,
                    last,
                    value,
                    amplitude,
                    op,
                    fields[0],
                    loc,
                )
            )

    def _k_EQUATION(self, card: _Card) -> None:
        """Blocks of a term count line, then that many (node, dof, coefficient) triples."""
        self._check_params(card, allowed=set())
        self._need_data(card)
        lines = iter(card.lines)
        for fields, _, loc in lines:
            fields = [f for f in fields if f != ""]
            if len(fields) != 1:
                raise DeckError("*EQUATION: a line with the number of terms is expected", loc)
            count = self._int(fields[0], "number of terms", loc)
            if count < 1:
                raise DeckError(f"*EQUATION: number of terms must be >= 1, got {count}", loc)
            tokens: list[str] = []
            for more, _, more_loc in lines:
                more = [f for f in more if f != ""]
                if len(more) % 3 or len(tokens) + len(more) > 3 * count:
                    raise DeckError(
                        f"*EQUATION: {count} terms (node, dof, coefficient) expected; this line "
                        f"has {len(more)} fields after {len(tokens) // 3} terms",
                        more_loc,
                    )
                tokens += more
                if len(tokens) == 3 * count:
                    break
            if len(tokens) != 3 * count:
                raise DeckError(f"*EQUATION: {count} terms expected, the card ends before", loc)
            nodes = []
            for token in tokens[0::3]:
                ids = self._nodes_of(token, card, loc)
                if ids.size != 1:
                    raise DeckError(
                        f"*EQUATION: node set {token} has {ids.size} nodes, one is needed", loc
                    )
                nodes.append(int(ids[0]))
            dofs = [self._dof(t, loc) for t in tokens[1::3]]
            coefficients = [self._float(t, "coefficient", loc) for t in tokens[2::3]]
            if coefficients[0] == 0.0:
                raise DeckError("*EQUATION: the first (dependent) coefficient is zero", loc)
            self.equations.append(Equation(
                _frozen_array(nodes, np.int64), _frozen_array(dofs, np.int64),
                _frozen_array(coefficients, np.float64), loc,
            ))  # fmt: skip

    # -- steps ----------------------------------------------------------------------------------

    def _k_STEP(self, card: _Card) -> None:
        if self.step is not None:
            raise DeckError(f"*STEP inside the step started at {self.step.location}", card.location)
        self._check_params(card, allowed={"NLGEOM", "INC", "INCF"})
        self._no_data(card)
        nlgeom = card.params.get("NLGEOM", "NO" if not self.nlgeom else "YES")
        if nlgeom not in (None, "YES", "NO"):
            raise DeckError(f"NLGEOM={nlgeom}: use NLGEOM or NLGEOM=YES/NO", card.location)
        self.nlgeom = nlgeom != "NO"
        inc = 100
        if "INC" in card.params:
            inc = self._int(card.params["INC"] or "", "INC", card.location)
            if inc <= 0:
                raise DeckError(f"INC must be > 0, got {inc}", card.location)
        self.step = _StepBuilder(len(self.steps) + 1, self.nlgeom, inc, card.location)
        self.context = None

    def _k_STATIC(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"DIRECT", "SOLVER", "TIMERESET", "TOTALTIMEATSTART",
                                          "EXPLICIT"})  # fmt: skip
        if step.static is not None:
            raise DeckError("a step can have only one *STATIC card", card.location)
        values: tuple[float | None, ...] = ()
        if card.lines:
            fields, _, loc = card.lines[0]
            if len(card.lines) > 1 or len(fields) > 5:
                raise DeckError(
                    "*STATIC data line: initial increment, period, minimum, maximum", loc
                )
            values = self._floats_line(fields[:4], "*STATIC", loc)
        values = values + (None,) * (4 - len(values))
        for name, value in zip(("initial increment", "period", "minimum", "maximum"), values):
            if value is not None and value <= 0.0 and name != "minimum":
                raise DeckError(f"*STATIC {name} must be > 0, got {value}", card.location)
        total_at_start = None
        if "TOTALTIMEATSTART" in card.params:
            total_at_start = self._float(
                card.params["TOTALTIMEATSTART"] or "", "TOTAL TIME AT START", card.location
            )
        step.static = Static(
            initial_increment=values[0] if values[0] is not None else 1.0,
            period=values[1] if values[1] is not None else 1.0,
            minimum=values[2],
            maximum=values[3],
            direct="DIRECT" in card.params,
            time_reset="TIMERESET" in card.params,
            total_time_at_start=total_at_start,
        )

    def _k_DYNAMIC(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"DIRECT", "ALPHA", "SOLVER", "EXPLICIT"})
        if "EXPLICIT" in card.params:
            raise DeckError(
                "*DYNAMIC, EXPLICIT is not supported yet (implicit only)", card.location
            )
        if step.static is not None:
            raise DeckError("a step can have only one *STATIC or *DYNAMIC card", card.location)
        alpha = -0.05
        if "ALPHA" in card.params:
            alpha = self._float(card.params["ALPHA"] or "", "ALPHA", card.location)
            if not -1.0 / 3.0 <= alpha <= 0.0:
                raise DeckError(f"*DYNAMIC ALPHA must be in [-1/3, 0], got {alpha}", card.location)
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(card.lines) > 1 or len(fields) > 5:
            raise DeckError(
                "*DYNAMIC data line: initial increment, period, minimum, maximum[, CFD increment]",
                loc,
            )
        values = self._floats_line(fields[:4], "*DYNAMIC", loc)
        values = values + (None,) * (4 - len(values))
        for name, value in zip(("initial increment", "period"), values[:2]):
            if value is None or value <= 0.0:
                raise DeckError(f"*DYNAMIC {name} must be given and > 0, got {value}", loc)
        step.static = Static(
            initial_increment=values[0],
            period=values[1],
            minimum=values[2],
            maximum=values[3],
            direct="DIRECT" in card.params,
        )
        step.dynamic = Dynamic(alpha=alpha)

    def _k_INITIALCONDITIONS(self, card: _Card) -> None:
        self._check_params(card, allowed={"TYPE"}, required={"TYPE"})
        if card.params["TYPE"] != "VELOCITY":
            raise DeckError(
                "*INITIAL CONDITIONS is not supported yet for "
                f"TYPE={card.raw_params['TYPE']} (only TYPE=VELOCITY)",
                card.location,
            )
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 3:
                raise DeckError(
                    "*INITIAL CONDITIONS, TYPE=VELOCITY data line: node or node set, dof, value",
                    loc,
                )
            nodes = self._nodes_of(fields[0], card, loc)
            value = self._floats_line(fields[2:3], "*INITIAL CONDITIONS", loc)[0]
            self.initial_velocities.append(
                InitialVelocity(_frozen_array(nodes, np.int64), self._dof(fields[1], loc),
                                float(value or 0.0), loc)
            )  # fmt: skip

    def _k_CLOAD(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            if len(fields) != 3:
                raise DeckError("*CLOAD data line: node or node set, dof, value", loc)
            nodes = self._nodes_of(fields[0], card, loc)
            dof = self._dof(fields[1], loc)
            value = self._float(fields[2], "load", loc)
            step.cloads.append(CLoad(_frozen_array(nodes, np.int64), dof, value, amplitude, op,
                                     fields[0], loc))  # fmt: skip

    def _k_DLOAD(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"OP", "AMPLITUDE"})
        op, amplitude = self._op(card), self._amplitude_param(card)
        for fields, _, loc in card.lines:
            label = fields[1] if len(fields) > 1 else ""
            if label and not re.fullmatch(r"P[1-6]", label):
                raise DeckError(
                    f"*DLOAD load type {label} is not supported yet (only uniform pressure P1..P6)",
                    loc,
                )
            if len(fields) != 3:
                raise DeckError("*DLOAD data line: element or element set, P1..P6, pressure", loc)
            elements = self._elements_of(fields[0], card, loc)
            self.element_refs.append((f"{card.name} face {label}", elements, loc))
            value = self._float(fields[2], "pressure", loc)
            step.dloads.append(DLoad(_frozen_array(elements, np.int64), int(label[1]), value,
                                     amplitude, op, fields[0], loc))  # fmt: skip

    def _print_card(self, card: _Card, kind: str) -> None:
        step = self._in_step(card)
        set_param = {"NODE": "NSET", "EL": "ELSET", "CONTACT": "NSET"}[kind]
        allowed = {set_param, "TOTALS", "FREQUENCY", "FREQUENCYF", "GLOBAL"}
        required = {set_param} if kind != "CONTACT" else set()
        self._check_params(card, allowed=allowed, required=required)
        totals = card.params.get("TOTALS") or "NO"
        if totals not in ("YES", "NO", "ONLY"):
            raise DeckError(f"TOTALS={totals}: use YES, NO or ONLY", card.location)
        set_name = None
        if kind != "CONTACT":  # ccx ignores NSET on *CONTACT PRINT (docs/method.md §8.5)
            set_name = card.params[set_param] or ""
            sets = self.nsets if kind == "NODE" else self.elsets
            if set_name not in sets:
                raise DeckError(
                    f"{'node' if kind == 'NODE' else 'element'} set {set_name} is not defined "
                    "(before this line)",
                    card.location,
                )
        self._need_data(card)
        keys = tuple(k for fields, _, _ in card.lines for k in fields if k != "")
        if kind == "CONTACT":  # ccx reads the first four characters only (CDISP is CDIS)
            keys = tuple(k[:4] for k in keys)
        for key in keys:
            if key not in _PRINT_KEYS[kind]:
                raise DeckError(
                    f"{card.name} key {key} is not supported yet (supported: "
                    f"{', '.join(_PRINT_KEYS[kind])})",
                    card.location,
                )
        frequency = self._frequency(card)
        if not any(p.kind == kind for p in step.new_prints):
            self.prints = [p for p in self.prints if p.kind != kind]
        request = PrintRequest(kind, keys, set_name, totals, frequency, card.location)
        step.new_prints.append(request)
        self.prints.append(request)

    def _k_NODEPRINT(self, card: _Card) -> None:
        self._print_card(card, "NODE")

    def _k_ELPRINT(self, card: _Card) -> None:
        self._print_card(card, "EL")

    def _k_CONTACTPRINT(self, card: _Card) -> None:
        self._print_card(card, "CONTACT")

    def _file_card(self, card: _Card) -> None:
        step = self._in_step(card)
        kind = _FILE_KEYWORDS[card.keyword]
        self._check_params(card, allowed={"NSET", "ELSET", "FREQUENCY", "FREQUENCYF", "GLOBAL",
                                          "OUTPUT", "LASTITERATIONS", "CONTACTELEMENTS",
                                          "SECTIONFORCES"})  # fmt: skip
        keys = tuple(k for fields, _, _ in card.lines for k in fields if k != "")
        set_name = card.params.get("NSET") or card.params.get("ELSET")
        frequency = self._frequency(card)
        if not any(r.kind == kind for r in step.new_files):
            self.files = [r for r in self.files if r.kind != kind]
        request = FileRequest(card.name, kind, keys, set_name, "CONTACTELEMENTS" in card.params,
                              frequency, card.location)  # fmt: skip
        step.new_files.append(request)
        self.files.append(request)

    _k_NODEFILE = _k_NODEOUTPUT = _k_ELFILE = _k_ELEMENTOUTPUT = _file_card
    _k_CONTACTFILE = _k_CONTACTOUTPUT = _file_card

    def _k_CONTROLS(self, card: _Card) -> None:
        self._in_step(card)
        self._check_params(card, allowed={"PARAMETERS", "RESET"})
        if "RESET" in card.params:
            self._no_data(card)
            self.controls = {}
            return
        if "PARAMETERS" not in card.params or not card.params["PARAMETERS"]:
            raise DeckError("*CONTROLS needs PARAMETERS=... or RESET", card.location)
        self._need_data(card)
        self.controls[card.params["PARAMETERS"]] = tuple(
            self._floats_line(fields, "*CONTROLS", loc) for fields, _, loc in card.lines
        )

    def _k_CHANGEFRICTION(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"INTERACTION"}, required={"INTERACTION"})
        self._no_data(card)
        name = card.params["INTERACTION"] or ""
        if name not in self.interactions:
            raise DeckError(f"surface interaction {name} is not defined", card.location)
        step.pending_friction = (name, card.location)

    def _k_MODELCHANGE(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed={"TYPE", "ADD", "REMOVE"}, required={"TYPE"})
        if card.params["TYPE"] != "CONTACTPAIR":
            raise DeckError(
                f"*MODEL CHANGE, TYPE={card.params['TYPE']} is not supported yet "
                "(only TYPE=CONTACT PAIR)",
                card.location,
            )
        if ("ADD" in card.params) == ("REMOVE" in card.params):
            raise DeckError("*MODEL CHANGE needs exactly one of ADD and REMOVE", card.location)
        action = "ADD" if "ADD" in card.params else "REMOVE"
        self._need_data(card)
        for fields, _, loc in card.lines:
            if len(fields) != 2:
                raise DeckError("*MODEL CHANGE data line: slave surface, master surface", loc)
            step.model_changes.append(ModelChange(action, fields[0], fields[1], loc))

    def _k_ENDSTEP(self, card: _Card) -> None:
        step = self._in_step(card)
        self._check_params(card, allowed=set())
        self._no_data(card)
        if step.static is None:
            raise DeckError(
                "the step has no *STATIC or *DYNAMIC procedure (the only ones supported)",
                step.location,
            )
        if step.pending_friction is not None:
            raise DeckError("*CHANGE FRICTION without a following *FRICTION",
                            step.pending_friction[1])  # fmt: skip
        self.steps.append(
            Step(
                number=step.number,
                nlgeom=step.nlgeom,
                max_increments=step.max_increments,
                static=step.static,
                boundaries=tuple(step.boundaries),
                cloads=tuple(step.cloads),
                dloads=tuple(step.dloads),
                prints=tuple(self.prints),
                file_requests=tuple(self.files),
                output_frequency=self.frequency,
                controls=dict(self.controls),
                friction_changes=tuple(step.friction_changes),
                model_changes=tuple(step.model_changes),
                location=step.location,
                dynamic=step.dynamic,
            )
        )
        self.step = None

    def _ignore(self, card: _Card, reason: str) -> None:
        """Skip a keyword, keeping the FREQUENCY it sets for every output (ccx rule)."""
        if "FREQUENCY" in card.params and card.keyword in _SETS_FREQUENCY:
            self._frequency(card)
        self.ignored.append((card.name, card.location.file, card.location.line))
        self.warnings.append(DeckWarning(card.name, None, reason, card.location))

    # -- final checks and assembly --------------------------------------------------------------

    def _finish(self) -> Deck:
        node_ids, node_coords = self._assemble_nodes()
        elements = self._assemble_elements()
        all_elements = (
            np.sort(np.concatenate([b.ids for b in elements.values()]))
            if elements
            else np.zeros(0, np.int64)
        )
        for block in elements.values():
            self._check_known(node_ids, block.connectivity, "node", "element connectivity",
                              block.locations)  # fmt: skip
        for what, ids, loc in self.node_refs:
            self._check_known(node_ids, ids, "node", what, (loc,))
        for what, ids, loc in self.element_refs:
            self._check_known(all_elements, ids, "element", what, (loc,))
        self._check_faces(elements)
        materials = self._check_materials(elements, all_elements)
        interactions = self._check_contact()
        for step in self.steps:
            for load in step.dloads:
                self._check_face_numbers(elements, load.elements, load.face, load.location)
            for change in step.model_changes:
                if not any((p.slave, p.master) == (change.slave, change.master)
                           for p in self.contact_pairs):  # fmt: skip
                    raise DeckError(
                        f"*MODEL CHANGE: no *CONTACT PAIR {change.slave}, {change.master}",
                        change.location,
                    )
        return Deck(
            path=str(self.path),
            heading="\n".join(self.heading),
            node_ids=node_ids,
            node_coords=node_coords,
            elements=elements,
            nsets={k: _frozen_array(v, np.int64) for k, v in self.nsets.items()},
            elsets={k: _frozen_array(v, np.int64) for k, v in self.elsets.items()},
            surfaces=dict(self.surfaces),
            materials=materials,
            sections=tuple(self.sections),
            interactions=interactions,
            contact_pairs=tuple(self.contact_pairs),
            amplitudes=dict(self.amplitudes),
            boundaries=tuple(self.boundaries),
            steps=tuple(self.steps),
            ignored=tuple(self.ignored),
            warnings=tuple(self.warnings),
            initial_velocities=tuple(self.initial_velocities),
            equations=tuple(self.equations),
        )

    def _assemble_nodes(self) -> tuple[np.ndarray, np.ndarray]:
        ids_array = np.array(self.node_ids, dtype=np.int64)
        coords_array = np.array(self.node_coords, dtype=np.float64).reshape(-1, 3)
        order = np.argsort(ids_array, kind="stable")
        ids_array, coords_array = ids_array[order], coords_array[order]
        duplicate = np.flatnonzero(np.diff(ids_array) == 0)
        if duplicate.size:
            node = int(ids_array[duplicate[0]])
            first, second = order[duplicate[0]], order[duplicate[0] + 1]
            raise DeckError(
                f"node {node} is defined twice (first at {self.node_locs[first]})",
                self.node_locs[second],
            )
        if np.any(ids_array <= 0):
            bad = int(np.argmin(ids_array))
            raise DeckError(
                f"node numbers must be > 0, got {int(ids_array[bad])}", self.node_locs[order[bad]]
            )
        ids_array.flags.writeable = False
        coords_array.flags.writeable = False
        return ids_array, coords_array

    def _assemble_elements(self) -> dict[str, ElementBlock]:
        blocks: dict[str, ElementBlock] = {}
        for name, etype in ELEMENT_TYPES.items():
            if not self.element_ids[name]:
                continue
            ids = np.array(self.element_ids[name], dtype=np.int64)
            conn = np.array(self.element_rows[name], dtype=np.int64).reshape(-1, etype.num_nodes)
            locations = tuple(self.element_locs[name])
            bad = np.flatnonzero(ids <= 0)
            if bad.size:
                raise DeckError(f"element {int(ids[bad[0]])} must be > 0", locations[bad[0]])
            ordered = np.sort(conn, axis=1)
            repeats = np.flatnonzero(np.any(ordered[:, 1:] == ordered[:, :-1], axis=1))
            if repeats.size:
                k = repeats[0]
                raise DeckError(f"element {int(ids[k])} repeats a node", locations[k])
            ids.flags.writeable = False
            conn.flags.writeable = False
            blocks[name] = ElementBlock(ELEMENT_TYPES[name], ids, conn, locations)
        all_ids = np.concatenate([b.ids for b in blocks.values()]) if blocks else np.zeros(0, int)
        all_locs = [loc for b in blocks.values() for loc in b.locations]
        order = np.argsort(all_ids, kind="stable")
        twice = np.flatnonzero(np.diff(all_ids[order]) == 0)
        if twice.size:
            first, second = order[twice[0]], order[twice[0] + 1]
            raise DeckError(
                f"element {int(all_ids[first])} is defined twice (first at {all_locs[first]})",
                all_locs[second],
            )
        return blocks

    @staticmethod
    def _check_known(known: np.ndarray, ids: np.ndarray, kind: str, what: str,
                     locations: tuple[Location, ...]) -> None:  # fmt: skip
        if ids.size == 0:
            return
        ok = np.isin(ids, known)
        if np.all(ok):
            return
        bad = np.argwhere(~ok)[0]
        loc = locations[bad[0]] if len(locations) > 1 else locations[0]
        number = int(ids[tuple(bad)])
        raise DeckError(f"{what} refers to {kind} {number}, which is not defined", loc)

    def _check_faces(self, elements: dict[str, ElementBlock]) -> None:
        for surface in self.surfaces.values():
            if surface.type == "ELEMENT":
                for face in np.unique(surface.faces):
                    mask = surface.faces == face
                    self._check_face_numbers(elements, surface.elements[mask], int(face),
                                             surface.location)  # fmt: skip

    @staticmethod
    def _check_face_numbers(elements: dict[str, ElementBlock], ids: np.ndarray, face: int,
                            location: Location) -> None:  # fmt: skip
        for block in elements.values():
            if face > block.type.num_faces:
                hit = np.isin(ids, block.ids)
                if np.any(hit):
                    element = int(ids[np.argmax(hit)])
                    raise DeckError(
                        f"face {face} of element {element}: {block.type.name} has faces "
                        f"1..{block.type.num_faces}",
                        location,
                    )

    def _check_materials(self, elements: dict[str, ElementBlock],
                         all_elements: np.ndarray) -> dict[str, Material]:  # fmt: skip
        owner: dict[int, SolidSection] = {}
        for section in self.sections:
            if section.material not in self.materials:
                raise DeckError(f"material {section.material} is not defined", section.location)
            if self.materials[section.material].elastic is None:
                raise DeckError(
                    f"material {section.material} has no *ELASTIC card",
                    self.materials[section.material].location,
                )
            for element in self.elsets[section.elset]:
                if element in owner and owner[element] is not section:
                    raise DeckError(
                        f"element {element} is in two solid sections (the other at "
                        f"{owner[element].location})",
                        section.location,
                    )
                owner[element] = section
        missing = all_elements[~np.isin(all_elements, np.fromiter(owner, np.int64, len(owner)))]
        if missing.size:
            element = int(missing[0])
            loc = next(
                b.locations[int(np.argmax(b.ids == element))]
                for b in elements.values()
                if np.any(b.ids == element)
            )
            raise DeckError(f"element {element} has no *SOLID SECTION (no material)", loc)
        return {
            name: Material(m.name, m.elastic, dict(m.extra), m.location)
            for name, m in self.materials.items()
        }

    def _check_contact(self) -> dict[str, SurfaceInteraction]:
        for pair in self.contact_pairs:
            if pair.interaction not in self.interactions:
                raise DeckError(
                    f"surface interaction {pair.interaction} is not defined", pair.location
                )
            if self.interactions[pair.interaction].behavior is None:
                raise DeckError(
                    f"surface interaction {pair.interaction} has no *SURFACE BEHAVIOR "
                    "(required for penalty contact)",
                    self.interactions[pair.interaction].location,
                )
            for role, name in (("slave", pair.slave), ("master", pair.master)):
                if name not in self.surfaces:
                    raise DeckError(f"{role} surface {name} is not defined", pair.location)
            if self.surfaces[pair.master].type != "ELEMENT":
                raise DeckError(
                    f"master surface {pair.master} must be made of element faces, not TYPE=NODE",
                    pair.location,
                )
        return {
            name: SurfaceInteraction(i.name, i.behavior, i.friction, dict(i.extra), i.location)
            for name, i in self.interactions.items()
        }


def read_deck(path: str | Path) -> Deck:
    """Read a CalculiX ``.inp`` deck (node-to-face contact subset) with its ``*INCLUDE`` files.

    Args:
        path: the deck file.

    Returns:
        The parsed ``Deck``.

    Raises:
        DeckError: (a ``ValueError``) bad, inconsistent or unsupported input; the message starts
            with ``file:line`` and names the keyword, number or set at fault.
    """
    return _Reader(Path(path)).read()
