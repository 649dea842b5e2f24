"""The parsed deck as frozen dataclasses: ``Deck``, its steps, sets, surfaces, materials, loads.

See docs/method.md §8.5. Every object keeps the ``Location`` of its card.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from ..elements import ElementType
from ..shell_expansion import ShellExpansion
from .errors import DeckWarning, Location


@dataclass(frozen=True, eq=False)
class ElementBlock:
    """All elements of one type: ``ids (E,)`` and ``connectivity (E, num_nodes)`` node ids."""

    type: ElementType
    ids: np.ndarray
    connectivity: np.ndarray
    locations: tuple[Location, ...] = ()


@dataclass(frozen=True, eq=False)
class SpringElements:
    """Spring elements of one type with the behaviour of one ``*SPRING`` card (§18.3).

    Attributes:
        type: ``SPRINGA``, ``SPRING1`` or ``SPRING2``.
        ids: ``(E,)`` element numbers.
        connectivity: ``(E, 2)`` node numbers (``(E, 1)`` for SPRING1).
        dofs: The degrees of freedom the spring acts in (1..3): none for SPRINGA, one for
            SPRING1, two for SPRING2.
        stiffness: The spring constant (linear springs), else None.
        table: ``(k, 2)`` rows ``(elongation, force)`` of ``NONLINEAR`` springs, else None.
        location: The ``*SPRING`` card.
    """

    type: str
    ids: np.ndarray
    connectivity: np.ndarray
    dofs: tuple[int, ...]
    stiffness: float | None
    table: np.ndarray | None
    location: Location


#: Key suffix of a ``TYPE=NODE`` surface that shares its name with an element surface: ccx
#: takes the node surface as a contact pair's slave and the element one as master (§30).
NODE_TWIN = "#NODES"


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
    """A ``*MATERIAL``: isotropic ``elastic = (E, nu)`` plus data a static step does not use.

    ``plastic`` is the ``*PLASTIC`` table (isotropic hardening) as ``(yield stress, equivalent
    plastic strain)`` rows, None for an elastic material; ``plastic_location`` its card.
    """

    name: str
    elastic: tuple[float, float] | None
    extra: dict[str, tuple[tuple[float | None, ...], ...]]
    location: Location
    plastic: tuple[tuple[float, float], ...] | None = None
    plastic_location: Location | None = None


@dataclass(frozen=True, eq=False)
class SolidSection:
    """A ``*SOLID SECTION``: material of the elements of ``elset``.

    ``thickness`` is the first value of its data line, if any: the out-of-plane thickness of
    plane strain and plane stress elements (ccx's default 1; ignored for 3D and CAX elements).
    ``orientation`` names its ``*ORIENTATION``, if any.
    """

    elset: str
    material: str
    location: Location
    thickness: float | None = None
    #: The ``ORIENTATION`` name (material axes; isotropic materials only, docs/method.md §41.3).
    orientation: str | None = None


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
class ContactDamping:
    """A ``*CONTACT DAMPING`` card: damping constant and ``TANGENT FRACTION`` (default 0)."""

    coefficient: float
    tangent_fraction: float
    location: Location


@dataclass(frozen=True, eq=False)
class SurfaceInteraction:
    """A ``*SURFACE INTERACTION`` with its behavior, optional friction, damping and extra data."""

    name: str
    behavior: SurfaceBehavior | None
    friction: Friction | None
    extra: dict[str, tuple[tuple[float | None, ...], ...]]
    location: Location
    damping: ContactDamping | None = None


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
class Film:
    """One ``*FILM`` data line: heat flow ``coefficient (T - sink)`` out of face ``face`` (1..6)."""

    elements: np.ndarray
    face: int
    sink: float
    coefficient: float
    op: str
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


@dataclass(frozen=True)
class Frequency:
    """``*FREQUENCY`` parameters and data line: the lowest ``num_eigenvalues`` modes.

    ``lower``/``upper`` bound the frequencies [cycles/time] (None: not given); ``storage`` is
    STORAGE=YES (ccx keeps the modes for a later modal step, no effect on the ``.dat``).
    """

    num_eigenvalues: int = 10
    lower: float | None = None
    upper: float | None = None
    storage: bool = False


@dataclass(frozen=True, eq=False)
class ModalDynamic:
    """``*MODAL DYNAMIC`` parameters; its data line (increments) is the step's ``static``.

    Attributes:
        variable: DIRECT=NO: increments grow by 1.5 up to the maximum, the last one cut to the
            step's end; else (ccx 2.20's default, also for a bare ``DIRECT``, which 2.20 does
            not recognize) fixed increments until the period is reached or passed.
        deltmx: DELTMX, the largest change of a modal force per increment, or None.
        location: The card.
    """

    variable: bool
    deltmx: float | None
    location: Location


@dataclass(frozen=True, eq=False)
class ModalDamping:
    """``*MODAL DAMPING, RAYLEIGH``: ``C = alpha M + beta K``."""

    alpha: float
    beta: float
    location: Location


@dataclass(frozen=True, eq=False)
class Coupled:
    """A ``*COUPLED TEMPERATURE-DISPLACEMENT`` or ``*HEAT TRANSFER`` procedure.

    Its increments are the step's ``static``.

    Attributes:
        steady: ``STEADY STATE`` (no heat capacity), else transient (backward Euler).
        deltmx: DELTMX, the largest temperature change per increment, or None.
        location: The card.
        alpha: The HHT parameter of the transient step's mechanics (ccx's ALPHA, -0.05).
        heat: A ``*HEAT TRANSFER`` step: the temperature alone, the mechanics not solved
            (docs/method.md §20.9).
    """

    steady: bool
    deltmx: float | None
    location: Location
    alpha: float = -0.05
    heat: bool = False


@dataclass(frozen=True, eq=False)
class InitialTemperature:
    """``*INITIAL CONDITIONS, TYPE=TEMPERATURE`` data line: ``value`` at ``nodes``."""

    nodes: np.ndarray
    value: float
    location: Location


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
    ``totals`` is ``NO``, ``YES`` or ``ONLY``; ``set`` is None for contact prints;
    ``time_points`` names the ``*TIME POINTS`` at which it prints (instead of ``frequency``).
    """

    kind: str
    keys: tuple[str, ...]
    set: str | None
    totals: str
    frequency: int | None
    location: Location
    time_points: str | None = None


@dataclass(frozen=True, eq=False)
class TimePoints:
    """A ``*TIME POINTS`` card: step times (ascending) at which requests with its name print."""

    name: str
    times: np.ndarray
    location: Location


@dataclass(frozen=True, eq=False)
class Gravity:
    """A ``*DLOAD ... GRAV`` line: the acceleration ``value * direction`` on ``elements``.

    The load is density times that acceleration per unit volume (ccx's gravity load).
    """

    elements: np.ndarray
    value: float
    direction: np.ndarray
    amplitude: str | None
    op: str
    target: str
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
        location: where the ``*STEP`` card is (file and line).
        dynamic: the ``*DYNAMIC`` parameters, or None for a static step.
        frequency: the ``*FREQUENCY`` procedure (a modal step; ``static`` is then unused), or
            None.
        coupled: the ``*COUPLED TEMPERATURE-DISPLACEMENT`` procedure (its increments in
            ``static``), or None.
        temperatures: the ``*BOUNDARY`` lines of dof 11 (temperatures) of this step.
        modal_dynamic: the ``*MODAL DYNAMIC`` procedure (its increments in ``static``), or None.
        modal_damping: the effective ``*MODAL DAMPING`` (carried over from earlier steps), or
            None.
        temperature_fields: the ``*TEMPERATURE`` data lines of this step (node or node set and
            temperature, in order; the model accepts them where they keep the initial
            temperatures, docs/method.md §26.2).
        gravity: the ``*DLOAD ... GRAV`` lines of this step, in deck order.
        cfluxes: the ``*CFLUX`` lines of this step (heat flow into nodes, dof 11), in deck
            order.
        dfluxes: the ``*DFLUX`` lines of this step (uniform heat flux into faces S1..S6; the
            ``face`` of each line), in deck order.
        films: the ``*FILM`` lines of this step (faces F1..F6), in deck order.
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
    frequency: Frequency | None = None
    coupled: Coupled | None = None
    temperatures: tuple[Boundary, ...] = ()
    modal_dynamic: ModalDynamic | None = None
    modal_damping: ModalDamping | None = None
    temperature_fields: tuple[InitialTemperature, ...] = ()
    gravity: tuple[Gravity, ...] = ()
    cfluxes: tuple[CLoad, ...] = ()
    dfluxes: tuple[DLoad, ...] = ()
    films: tuple[Film, ...] = ()

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
        """OP of the first ``*DLOAD`` card of the step, pressure or gravity (``MOD`` if none)."""
        first = min((*self.dloads[:1], *self.gravity[:1]), key=lambda d: d.location.line,
                    default=None)  # fmt: skip
        return first.op if first is not None else "MOD"

    def field_controls(self) -> dict[str, float | None]:
        """``*CONTROLS, PARAMETERS=FIELD`` values by name, ccx defaults where not given."""
        values = dict(FIELD_CONTROL_DEFAULTS)
        given = [v for line in self.controls.get("FIELD", ()) for v in line]
        for name, value in zip(FIELD_CONTROL_NAMES, given):
            if value is not None:
                values[name] = value
        return values


@dataclass(frozen=True, eq=False)
class Tie:
    """A ``*TIE``: ``slave`` (dependent) and ``master`` surface names.

    ``position_tolerance`` is None for ccx's default; ``adjust`` is False for ``ADJUST=NO``;
    ``cyclic`` marks a ``CYCLIC SYMMETRY`` tie (used by a :class:`CyclicSymmetry`).
    """

    name: str
    slave: str
    master: str
    position_tolerance: float | None
    adjust: bool
    cyclic: bool
    location: Location


@dataclass(frozen=True, eq=False)
class CyclicSymmetry:
    """A ``*CYCLIC SYMMETRY MODEL``: ``num_sectors`` (N) about the axis from a to b.

    The sector's faces are those of the cyclic ``tie``; ``check`` compares the geometry's sector
    angle with 2π/N (ccx's CHECK).
    """

    tie: str
    num_sectors: float
    point_a: tuple[float, float, float]
    point_b: tuple[float, float, float]
    check: bool
    location: Location


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
        initial_velocities: ``*INITIAL CONDITIONS, TYPE=VELOCITY`` data lines, in deck order.
        springs: spring elements (SPRINGA, SPRING1, SPRING2) by ``*SPRING`` card.
        ties: ``*TIE`` cards in deck order; cyclic_symmetries: ``*CYCLIC SYMMETRY MODEL`` cards.
        initial_temperatures: ``*INITIAL CONDITIONS, TYPE=TEMPERATURE`` data lines, in order.
        temperature_boundaries: ``*BOUNDARY`` lines of dof 11 of the model definition.
        transformed_nodes: sorted numbers of the nodes of a ``*TRANSFORM`` (their ``*BOUNDARY``
            lines are rewritten in global dofs, ``deck/transforms.py``).
        shells: the shell nodes and their expanded nodes when the deck had S8/S8R elements
            (replaced by their C3D20/C3D20R bricks in ``elements``, docs/method.md §24), else None.
        time_points: ``*TIME POINTS`` cards by upper-case name.
        wedges: sorted numbers of the C3D6 elements, which ``elements`` holds as C3D8 with one
            collapsed edge (``deck/wedges.py``, docs/method.md §30).
        wedge_nodes: ``(W, 6)`` the wedges' nodes as the deck gives them (ccx's order, before
            the turning of §30.1), rows in the order of ``wedges``: the ``.frd`` writes them.
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
    springs: tuple[SpringElements, ...] = ()
    ties: tuple[Tie, ...] = ()
    cyclic_symmetries: tuple[CyclicSymmetry, ...] = ()
    initial_temperatures: tuple[InitialTemperature, ...] = ()
    temperature_boundaries: tuple[Boundary, ...] = ()
    shells: ShellExpansion | None = None
    transformed_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    time_points: dict[str, TimePoints] = field(default_factory=dict)
    wedges: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    wedge_nodes: np.ndarray = field(default_factory=lambda: np.zeros((0, 6), np.int64))

    @property
    def num_elements(self) -> int:
        """Total number of elements, springs included (ccx numbers contact elements after them)."""
        solids = sum(int(b.ids.size) for b in self.elements.values())
        return solids + sum(int(s.ids.size) for s in self.springs)

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
