"""The state of a deck being read and the field parsers every card handler uses."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..elements import ELEMENT_TYPES
from .data import (
    Amplitude,
    Boundary,
    CLoad,
    ContactDamping,
    ContactPair,
    Coupled,
    CyclicSymmetry,
    DLoad,
    Dynamic,
    Equation,
    FileRequest,
    Film,
    Frequency,
    Friction,
    FrictionChange,
    Gravity,
    InitialTemperature,
    InitialVelocity,
    ModalDamping,
    ModalDynamic,
    ModelChange,
    PrintRequest,
    SolidSection,
    Static,
    Step,
    Surface,
    SurfaceBehavior,
    Tie,
    TimePoints,
)
from .errors import DeckError, DeckWarning, Location
from .leniency import SETS_FREQUENCY
from .lexer import INT_RE, Card, check_params


@dataclass
class StepBuilder:
    """A ``*STEP`` being read: its cards so far."""

    number: int
    nlgeom: bool
    max_increments: int
    location: Location
    static: Static | None = None
    dynamic: Dynamic | None = None
    frequency: Frequency | None = None
    coupled: Coupled | None = None
    modal_dynamic: ModalDynamic | None = None
    boundaries: list[Boundary] = field(default_factory=list)
    temperatures: list[Boundary] = field(default_factory=list)
    temperature_fields: list[InitialTemperature] = field(default_factory=list)
    cloads: list[CLoad] = field(default_factory=list)
    cfluxes: list[CLoad] = field(default_factory=list)
    dfluxes: list[DLoad] = field(default_factory=list)
    films: list[Film] = field(default_factory=list)
    dloads: list[DLoad] = field(default_factory=list)
    gravity: list[Gravity] = field(default_factory=list)
    new_prints: list[PrintRequest] = field(default_factory=list)
    new_files: list[FileRequest] = field(default_factory=list)
    friction_changes: list[FrictionChange] = field(default_factory=list)
    model_changes: list[ModelChange] = field(default_factory=list)
    pending_friction: tuple[str, Location] | None = None


@dataclass
class MaterialBuilder:
    """A ``*MATERIAL`` being read: its cards so far."""

    name: str
    location: Location
    elastic: tuple[float, float] | None = None
    elastic_location: Location | None = None
    #: ``*ELASTIC`` rows ``(E, nu, temperature or None)`` and their lines; ``elastic`` is the
    #: first row until the deck's temperatures are known (``checks._check_materials``).
    elastic_rows: tuple[tuple[float, float, float | None], ...] = ()
    elastic_row_locations: tuple[Location, ...] = ()
    plastic: tuple[tuple[float, float], ...] | None = None
    plastic_location: Location | None = None
    extra: dict[str, tuple[tuple[float | None, ...], ...]] = field(default_factory=dict)
    #: The data lines of each card of ``extra``.
    extra_locations: dict[str, tuple[Location, ...]] = field(default_factory=dict)


@dataclass
class InteractionBuilder:
    """A ``*SURFACE INTERACTION`` being read: its cards so far."""

    name: str
    location: Location
    behavior: SurfaceBehavior | None = None
    friction: Friction | None = None
    damping: ContactDamping | None = None
    extra: dict[str, tuple[tuple[float | None, ...], ...]] = field(default_factory=dict)


class ReaderState:
    """What has been read so far, and the helpers that parse and check card fields."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.heading: list[str] = []
        self.node_ids: list[int] = []
        self.node_coords: list[tuple[float, float, float]] = []
        self.node_locs: list[Location] = []
        self.element_rows: dict[str, list[list[int]]] = {t: [] for t in ELEMENT_TYPES}
        self.element_ids: dict[str, list[int]] = {t: [] for t in ELEMENT_TYPES}
        self.element_locs: dict[str, list[Location]] = {t: [] for t in ELEMENT_TYPES}
        #: The C3D6 elements (numbers, node rows, locations), made collapsed C3D8 once read
        #: (``wedges.py``).
        self.wedge_ids: list[int] = []
        self.wedge_rows: list[list[int]] = []
        self.wedge_locs: list[Location] = []
        #: Spring elements by type: (element number, nodes, location) (``springs.py``).
        self.spring_rows: dict[str, list[tuple[int, list[int], Location]]] = {}
        #: Shell elements in deck order: (type, element number, nodes, location) (``shells.py``).
        self.shell_rows: list[tuple[str, int, list[int], Location]] = []
        #: ``*SHELL SECTION`` cards (``shells.ShellSection``) and SPOS/SNEG faces (ids, location).
        self.shell_sections: list = []
        self.shell_face_refs: list[tuple[np.ndarray, Location]] = []
        #: ``*SPRING`` cards: (card, dofs, stiffness or None, table or None).
        self._spring_behaviors: list[
            tuple[Card, tuple[int, ...], float | None, np.ndarray | None]
        ] = []
        self.nsets: dict[str, list[int]] = {}
        self.elsets: dict[str, list[int]] = {}
        self.set_locations: dict[tuple[str, str], Location] = {}
        self.surfaces: dict[str, Surface] = {}
        self.materials: dict[str, MaterialBuilder] = {}
        self.sections: list[SolidSection] = []
        #: ``*ORIENTATION`` cards by name (``orientations.Orientation``).
        self.orientations: dict = {}
        self.interactions: dict[str, InteractionBuilder] = {}
        self.contact_pairs: list[ContactPair] = []
        self.amplitudes: dict[str, Amplitude] = {}
        self.time_points: dict[str, TimePoints] = {}
        self.boundaries: list[Boundary] = []
        self.initial_velocities: list[InitialVelocity] = []
        self.initial_temperatures: list[InitialTemperature] = []
        self.temperature_boundaries: list[Boundary] = []
        self.equations: list[Equation] = []
        #: ``*TRANSFORM`` cards (``transforms.Transform``), in deck order.
        self.transforms: list = []
        self.ties: dict[str, Tie] = {}
        self.cyclic_symmetries: list[CyclicSymmetry] = []
        self.steps: list[Step] = []
        self.ignored: list[tuple[str, str, int]] = []
        self.warnings: list[DeckWarning] = []
        self.step: StepBuilder | None = None
        self.context: MaterialBuilder | InteractionBuilder | None = None
        # carried over between steps
        self.prints: list[PrintRequest] = []
        self.files: list[FileRequest] = []
        self.controls: dict[str, tuple[tuple[float | None, ...], ...]] = {}
        self.frequency = 1
        self.nlgeom = False
        self.modal_damping: ModalDamping | None = None
        # checks done once everything is read: (what, ids, location)
        self.node_refs: list[tuple[str, np.ndarray, Location]] = []
        self.element_refs: list[tuple[str, np.ndarray, Location]] = []

    _check_params = staticmethod(check_params)

    @staticmethod
    def _no_data(card: Card) -> None:
        if card.lines:
            raise DeckError(f"{card.name} takes no data lines", card.lines[0][2])

    @staticmethod
    def _need_data(card: Card) -> None:
        if not card.lines:
            raise DeckError(f"{card.name} needs a data line", card.location)

    @staticmethod
    def _new_name(card: Card, defined: dict, what: str) -> str:
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
        if not INT_RE.match(token):
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

    def _procedure_line(
        self, card: Card, keyword: str, usage: str, count: int, most: int
    ) -> tuple[float | None, ...]:
        """The one data line of a procedure card (``*STATIC``, ``*FREQUENCY``, ...), if any.

        Its first ``count`` numbers, None where absent or empty; more than ``most`` fields or a
        second line is an error naming ``keyword`` and spelling the line's ``usage``.
        """
        values: tuple[float | None, ...] = ()
        if card.lines:
            fields, _, loc = card.lines[0]
            if len(card.lines) > 1 or len(fields) > most:
                raise DeckError(f"{keyword} data line: {usage}", loc)
            values = self._floats_line(fields[:count], keyword, loc)
        return values + (None,) * (count - len(values))

    def _nodes_of(self, token: str, card: Card, loc: Location) -> np.ndarray:
        if INT_RE.match(token):
            ids = np.array([int(token)], dtype=np.int64)
            self.node_refs.append((f"{card.name}", ids, loc))
            return ids
        if token not in self.nsets:
            raise DeckError(f"node set {token} is not defined (before this line)", loc)
        return np.array(self.nsets[token], dtype=np.int64)

    def _elements_of(self, token: str, card: Card, loc: Location) -> np.ndarray:
        if INT_RE.match(token):
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

    def _boundary_dof(self, token: str, loc: Location) -> int:
        """A ``*BOUNDARY`` dof: 1..6 (4..6, rotations, only on shell nodes: ``shells.py``)."""
        dof = self._int(token, "degree of freedom", loc)
        if dof not in range(1, 7):
            raise DeckError(f"degree of freedom {dof} is not supported (dofs are 1 to 6)", loc)
        return dof

    def _op(self, card: Card) -> str:
        op = card.params.get("OP") or "MOD"
        if op not in ("NEW", "MOD"):
            raise DeckError(f"OP={op} of {card.name}: use OP=NEW or OP=MOD", card.location)
        return op

    def _frequency(self, card: Card) -> int | None:
        if "FREQUENCY" not in card.params:
            return None
        value = self._int(card.params["FREQUENCY"] or "", "FREQUENCY", card.location)
        if value < 0:
            raise DeckError(f"FREQUENCY must be >= 0, got {value}", card.location)
        self.frequency = value
        return value

    def _in_step(self, card: Card) -> StepBuilder:
        if self.step is None:
            raise DeckError(f"{card.name} is a step keyword: it must follow *STEP", card.location)
        return self.step

    def _first_procedure(self, step: StepBuilder, card: Card) -> None:
        """Refuse a procedure card (``*STATIC``, ``*DYNAMIC``, ...) in a step that has one."""
        if step.static is not None or step.frequency is not None:
            raise DeckError("a step can have only one procedure card", card.location)

    def _ignore(self, card: Card, reason: str) -> None:
        """Skip a keyword, keeping the FREQUENCY it sets for every output (ccx rule)."""
        if "FREQUENCY" in card.params and card.keyword in SETS_FREQUENCY:
            self._frequency(card)
        self.ignored.append((card.name, card.location.file, card.location.line))
        self.warnings.append(DeckWarning(card.name, None, reason, card.location))
