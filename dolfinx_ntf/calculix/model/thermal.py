"""The temperature field of a deck with thermal steps (coupled or ``*HEAT TRANSFER``).

docs/method.md §20.8. :class:`ThermalModel` holds the temperature ``T`` (a scalar Lagrange space
numbered like the displacement's), the material data per cell (``*CONDUCTIVITY``, ``*SPECIFIC
HEAT``, ``*DENSITY``, ``*EXPANSION``), the heat residual with CalculiX's backward-Euler capacity
term, the temperature conditions (``*BOUNDARY`` dof 11) of every step, the initial temperatures
and one :class:`~dolfinx_ntf.GapConductance` per contact pair (``*GAP CONDUCTANCE``). The
mechanical residual takes ccx's thermal strain (measured against ccx 2.20 with C3D8): from the mean
temperature of each element (:class:`~dolfinx_ntf.fem.thermal.CellTemperature`), measured from the
initial temperature, ``x = alpha (T_c - T_init,c)`` subtracted from the diagonal of the
displacement gradient before the strain is formed.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import LinearConstraintBlock
from dolfinx_ntf.fem.serendipity_wedge import wedge_serendipity_constraints
from dolfinx_ntf.fem.thermal import CellTemperature
from dolfinx_ntf.kernels.gap_conductance import GapConductance

from ..deck import Boundary, Deck, DLoad, ElementBlock, Film
from .c3d15 import C3D15Films, c3d15_face_flows, c3d15_films

__all__ = ["ThermalModel", "is_thermal", "thermal_model"]

#: The material cards of the heat problem and the step kind that needs each.
_CARDS = {"*CONDUCTIVITY": "steady", "*SPECIFIC HEAT": "transient", "*DENSITY": "transient"}


def is_thermal(deck: Deck) -> bool:
    """True if the deck has a coupled step; refuses temperature input without one.

    Initial temperatures alone (no ``*BOUNDARY`` dof 11) in steps that are not coupled are no
    thermal problem: the temperature never changes, so the thermal strain is 0.

    Raises:
        NotImplementedError: temperature conditions (dof 11) with steps that are not coupled
            (their thermal strains are not supported), or mixed step kinds.
    """
    coupled = [step.coupled is not None for step in deck.steps]
    inputs = [
        *deck.initial_temperatures,
        *(t for step in deck.steps for t in step.temperature_fields),
        *deck.temperature_boundaries,
        *(b for step in deck.steps for b in step.temperatures),
    ]
    for step in deck.steps:
        kinds = (("*CFLUX", step.cfluxes), ("*DFLUX", step.dfluxes), ("*FILM", step.films))
        for name, cards in kinds:
            if cards and step.coupled is None:
                raise NotImplementedError(
                    f"{cards[0].location}: {name} in step {step.number}, which is not "
                    "*COUPLED TEMPERATURE-DISPLACEMENT or *HEAT TRANSFER: heat flows are "
                    "supported in thermal steps only"
                )
    heat = {step.coupled.heat for step in deck.steps if step.coupled is not None}
    if len(heat) > 1:
        raise NotImplementedError(
            f"{deck.steps[0].location}: *HEAT TRANSFER and *COUPLED TEMPERATURE-DISPLACEMENT "
            "steps in one deck are not supported yet"
        )
    if any(coupled) and not all(coupled):
        step = deck.steps[coupled.index(False)]
        raise NotImplementedError(
            f"{step.location}: step {step.number} is not *COUPLED TEMPERATURE-DISPLACEMENT or "
            "*HEAT TRANSFER while another step is: mixing thermal and other steps is not "
            "supported yet"
        )
    changes = [*deck.temperature_boundaries, *(b for step in deck.steps for b in step.temperatures)]
    fields = [t for step in deck.steps for t in step.temperature_fields]
    if fields and any(coupled):
        raise NotImplementedError(
            f"{fields[0].location}: *TEMPERATURE in a *COUPLED TEMPERATURE-DISPLACEMENT or *HEAT "
            "TRANSFER deck is not supported yet"
        )
    if fields:
        _check_unchanged(deck)
    if inputs and not changes and not any(coupled):
        # initial temperatures that never change: ccx's thermal strain alpha (T - T_init) is 0
        # (measured on the bolt deck: its *EXPANSION changes no printed digit, §26)
        logging.getLogger("dolfinx_ntf.details").info(
            " %s: initial temperatures without a temperature change: no thermal strain",
            inputs[0].location,
        )
        return False
    if inputs and not any(coupled):
        where = inputs[0].location
        raise NotImplementedError(
            f"{where}: temperatures (*INITIAL CONDITIONS, TYPE=TEMPERATURE or *BOUNDARY dof 11) "
            "are supported in *COUPLED TEMPERATURE-DISPLACEMENT and *HEAT TRANSFER steps only"
        )
    return any(coupled)


def _check_unchanged(deck: Deck) -> None:
    """Refuse ``*TEMPERATURE`` lines that change a node's temperature from its initial one.

    Such a field would give static steps a thermal strain, which is not supported; lines that
    restate the initial temperatures (Debian 13's bolt deck) change nothing (§26.2).
    """
    initial = {}
    for card in deck.initial_temperatures:
        initial.update(dict.fromkeys(card.nodes.tolist(), card.value))
    for step in deck.steps:
        current = dict(initial)
        for card in step.temperature_fields:
            current.update(dict.fromkeys(card.nodes.tolist(), card.value))
        for card in step.temperature_fields:
            changed = [n for n in card.nodes.tolist() if current[n] != initial.get(n)]
            if changed:
                raise NotImplementedError(
                    f"{card.location}: *TEMPERATURE changes the temperature of node {changed[0]} "
                    f"({initial.get(changed[0])} initially, {current[changed[0]]} in step "
                    f"{step.number}): thermal strains of static steps are not supported yet"
                )


@dataclass(eq=False)
class ThermalModel:
    """The temperature field of a deck (see the module docstring).

    Attributes:
        Q: Scalar Lagrange space of the displacement's degree (numbered like it).
        T: The temperature; ``T_old`` its value at the start of the increment.
        T_init: The initial temperature (reference of the thermal strain).
        cell_temperature: The element mean temperatures of ``T`` (the thermal strain's).
        T_init_c: The element mean initial temperatures.
        inverse_dt: Constant ``1/dt`` of the capacity term (0 in a steady step).
        alpha: Coefficient of thermal expansion per cell (DG0).
        conductivity: Conductivity per cell (DG0).
        residual: The heat residual ``rho c (T - T_old)/dt v + k grad T . grad v`` (ccx's
            quadrature).
        conductances: One gap conductance per contact pair (zero without ``*GAP CONDUCTANCE``).
        bc_dofs: Local dofs of ``Q`` with a prescribed temperature (the same in every step).
        bc_values: Per step, the prescribed temperatures at ``bc_dofs``.
        bc_value: Function holding the current prescribed values; ``bcs`` the conditions.
        constraints: C3D15: the face centres of ``Q`` (docs/method.md §39), else empty.
        strain_at_points: The thermal strain from ``T`` at the integration points (C3D15, §39)
            instead of the element mean temperature (C3D8, §20.8).
        flux: The current ``*CFLUX`` and ``*DFLUX`` heat flows into the nodes (``Q``'s dofs);
            ``flux_dofs`` the local dofs of the deck's nodes and ``flux_values`` their flows per
            step (§39).
        films: C3D15's ``*FILM`` terms (one per face type, on the heat problem's element terms)
            with the positions of their faces in ``film_values``' arrays; ``film_values`` per
            step the film coefficient and sink temperature of every face (§39).
    """

    Q: dolfinx.fem.FunctionSpace
    T: dolfinx.fem.Function
    T_old: dolfinx.fem.Function
    T_init: dolfinx.fem.Function
    cell_temperature: CellTemperature
    T_init_c: dolfinx.fem.Function
    inverse_dt: dolfinx.fem.Constant
    alpha: dolfinx.fem.Function
    conductivity: dolfinx.fem.Function
    residual: ufl.Form
    conductances: list[GapConductance]
    bc_dofs: np.ndarray
    bc_values: list[np.ndarray]
    bc_value: dolfinx.fem.Function
    bcs: list[compat.DirichletBC]
    constraints: list[LinearConstraintBlock]
    flux: dolfinx.fem.Function
    flux_dofs: np.ndarray
    flux_values: list[np.ndarray]
    films: list[tuple[C3D15Films, np.ndarray]]
    film_values: list[tuple[np.ndarray, np.ndarray]]
    strain_at_points: bool = False
    _steady: bool = False
    _start: np.ndarray | None = None
    _target: np.ndarray | None = None
    _flux_start: np.ndarray | None = None
    _flux_target: np.ndarray | None = None
    _film_start: list[np.ndarray] | None = None
    _step: int = 0

    def thermal_strain(self) -> ufl.core.expr.Expr:
        """``x I``, ``x = alpha (T_c - T_init,c)`` of the element mean temperatures.

        The mechanical strain is formed from ``grad u - x I`` (``bulk.stresses``): with
        ``NLGEOM`` its Green-Lagrange strain ``x^2/2`` off the small one where ``u = 0``, as ccx
        2.20's (measured, docs/method.md §20.8). With :attr:`strain_at_points` (C3D15) ``x =
        alpha (T - T_init)`` at each integration point, as ccx 2.20's C3D15 (measured, §39).
        """
        if self.strain_at_points:
            return self.alpha * (self.T - self.T_init) * ufl.Identity(3)
        x = self.alpha * (self.cell_temperature.T_c - self.T_init_c)
        return x * ufl.Identity(3)

    def begin_step(self, step_index: int, steady: bool) -> None:
        """Start a step: its prescribed temperatures and its kind (steady or transient).

        ccx applies the temperatures of a transient step at once and ramps those of a steady one
        from their values at the step start (manual, ``*COUPLED TEMPERATURE-DISPLACEMENT``).
        """
        self._step = step_index
        self._target = self.bc_values[step_index]
        self._start = self.T.x.array[self.bc_dofs].copy()
        self._flux_target = self.flux_values[step_index]
        self._flux_start = self.flux.x.array[self.flux_dofs].copy()
        self._film_start = [term.coefficient.copy() for term, _ in self.films]
        sink = self.film_values[step_index][1]
        for term, positions in self.films:  # the sink temperatures at once (measured, §39)
            term.sink[:] = sink[positions]
        self._steady = steady
        self.inverse_dt.value = 0.0

    def begin_increment(self, dt: float, fraction: float) -> None:
        """An attempt of size ``dt`` ending at ``fraction`` of the step.

        ``T`` restarts from ``T_old``, whose prescribed values are set to the new ones first: a
        prescribed temperature has no rate in the capacity term (as in ccx: its first increment
        gives the temperatures of ``rho c (T - T_old)/dt`` with the new boundary values in
        ``T_old``, measured on contact8). ``1/dt`` stays 0 in a steady step.
        """
        scale = fraction if self._steady else 1.0
        flux = self._flux_start + (self._flux_target - self._flux_start) * scale
        self.flux.x.array[self.flux_dofs] = flux  # ramped as the temperatures (measured, §39)
        coefficient = self.film_values[self._step][0]
        for (term, positions), start in zip(self.films, self._film_start):  # h ramped (§39)
            term.coefficient[:] = start + (coefficient[positions] - start) * scale
        values = self._start + (self._target - self._start) * scale
        for f in (self.bc_value, self.T_old):
            f.x.array[self.bc_dofs] = values
            _fill_centres(f, self.constraints)  # C3D15: T_old is C3D15's field of its nodes
            f.x.scatter_forward()
        self.T.x.array[:] = self.T_old.x.array
        self.T.x.scatter_forward()
        self.inverse_dt.value = 0.0 if self._steady else 1.0 / dt

    def end_increment(self) -> None:
        """A converged increment: its temperature becomes the next one's ``T_old``."""
        self.T_old.x.array[:] = self.T.x.array
        self.T_old.x.scatter_forward()


def _fill_centres(f: dolfinx.fem.Function, constraints: list[LinearConstraintBlock]) -> None:
    """Set the dependent (first) dof of every constraint row from its other terms (local).

    C3D15's face centres from their faces' 8 nodes (docs/method.md §39): a temperature given at
    the deck's nodes (initial, prescribed) is then C3D15's field. Every row's dofs are local
    (its face is in a local cell), so no communication is needed.
    """
    values = f.x.array
    for block in constraints:
        terms = block.coefficients[:, 1:] * values[block.nodes[:, 1:]]
        values[block.nodes[:, 0]] = (block.values - terms.sum(axis=1)) / block.coefficients[:, 0]


def _cell_values(
    deck: Deck, block: ElementBlock, element_cell: np.ndarray, Q0: dolfinx.fem.FunctionSpace,
    card: str, needed: bool,
) -> dolfinx.fem.Function:  # fmt: skip
    """A DG0 function of one constant material value per section (0 where not given)."""
    f = dolfinx.fem.Function(Q0)
    order = np.argsort(block.ids)
    for section in deck.sections:
        material = deck.materials[section.material]
        lines = material.extra.get(card)
        if lines is None:
            if needed:
                raise ValueError(
                    f"{section.location}: material {section.material} needs {card} for a "
                    "thermal step"
                )
            continue
        if len(lines) != 1 or not lines[0] or lines[0][0] is None or len(lines[0]) > 2:
            raise NotImplementedError(
                f"{material.location}: {card} of material {material.name}: only one constant "
                "value is supported (temperature-dependent or anisotropic data are not)"
            )
        if lines[0][0] < 0.0 or (lines[0][0] == 0.0 and needed):
            raise ValueError(
                f"{material.location}: {card} of material {material.name} must be > 0, got "
                f"{lines[0][0]}"
            )
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        rows = order[np.searchsorted(block.ids, members, sorter=order)]
        cells = element_cell[rows]
        f.x.array[compat.cell_dofs(Q0)[cells[cells >= 0], 0]] = lines[0][0]
    return f


def _bc_nodes(deck: Deck) -> tuple[np.ndarray, list[dict[int, float]]]:
    """The nodes with a prescribed temperature and their values per step (ccx's OP rules)."""
    current: dict[int, float] = {}
    per_step = []
    for b in deck.temperature_boundaries:
        _check_boundary(b)
        current.update(dict.fromkeys(b.nodes.tolist(), b.value))
    for step in deck.steps:
        if step.temperatures and step.temperatures[0].op == "NEW":
            current = {}
        for b in step.temperatures:
            _check_boundary(b)
            current.update(dict.fromkeys(b.nodes.tolist(), b.value))
        per_step.append(dict(current))
    nodes = sorted(per_step[0]) if per_step else []
    for step, values in zip(deck.steps, per_step):
        if sorted(values) != nodes:
            raise NotImplementedError(
                f"{step.location}: step {step.number} prescribes the temperature at other nodes "
                "than the first step: changing the nodes of dof 11 between steps is not "
                "supported yet"
            )
    return np.array(nodes, dtype=np.int64), per_step


def _nodal_flows(deck: Deck, block: ElementBlock) -> list[np.ndarray]:
    """Per step, ``(nodes,)`` heat flows into the deck's nodes: ``*CFLUX`` and ``*DFLUX``.

    ``*CLOAD``'s and ``*DLOAD``'s rules (docs/method.md §39): a value stays from step to step
    unless changed (``OP=MOD``) or removed (``OP=NEW``, the first card of a step); lines of one
    step on the same node (face) add up (measured against ccx 2.20 for ``*CFLUX``), and a step's
    first line on a node (face) replaces the earlier steps' value. ``*DFLUX`` faces: C3D15 only
    (nodal flows from the deck's faces, :func:`~.c3d15.c3d15_face_flows`).
    """
    nodes: dict[int, float] = {}
    faces: dict[tuple[int, int], float] = {}
    order = np.argsort(block.ids)
    per_step = []
    for step in deck.steps:
        for current, cards in ((nodes, step.cfluxes), (faces, step.dfluxes)):
            if cards and cards[0].op == "NEW":
                current.clear()
            touched: set = set()
            for card in cards:
                if card.amplitude is not None:
                    name = "*CFLUX" if current is nodes else "*DFLUX"
                    raise NotImplementedError(
                        f"{card.location}: {name} with an AMPLITUDE is not supported yet"
                    )
                if current is nodes:
                    keys = card.nodes.tolist()
                else:
                    rows = _loaded_face_rows(block, order, card, "*DFLUX", "S")
                    keys = [(int(r), card.face) for r in rows]
                for key in keys:
                    current[key] = (current[key] if key in touched else 0.0) + card.value
                    touched.add(key)
        flows = np.zeros(deck.node_ids.size)
        if nodes:
            np.add.at(flows, deck.node_index(np.array(list(nodes))), list(nodes.values()))
        if faces:
            keys = np.array(list(faces), dtype=np.int64)
            values = np.array(list(faces.values()))
            flows += c3d15_face_flows(deck, block, keys[:, 0], keys[:, 1], values)
        per_step.append(flows)
    return per_step


def _loaded_face_rows(
    block: ElementBlock, order: np.ndarray, card: DLoad | Film, name: str, label: str
) -> np.ndarray:
    """Block rows of the elements of a face-load ``card`` (``*DFLUX``, ``*FILM``), checked.

    ``order``: ``argsort(block.ids)``; ``label``: the card's load label letter (S, F).
    """
    if block.type.name != "C3D15":
        raise NotImplementedError(
            f"{card.location}: {name} on {block.type.name} faces is not supported yet "
            "(C3D15 only, docs/method.md §39)"
        )
    _check_face(card.face, block, card.location, name, label)
    return order[np.searchsorted(block.ids, card.elements, sorter=order)]


def _film_faces(
    deck: Deck, block: ElementBlock
) -> tuple[np.ndarray, list[tuple[np.ndarray, np.ndarray]]]:
    """The faces with a ``*FILM`` ``(K, 2)`` (element row, face); per step their ``h, T_sink``.

    Coefficients and sink temperatures are 0 where a face has no film in a step.

    A face keeps its film from step to step unless given again (its last line replaces it) or
    removed (``OP=NEW``, the first card of a step). C3D15 faces only (§39).
    """
    order = np.argsort(block.ids)
    current: dict[tuple[int, int], tuple[float, float]] = {}
    per_step = []
    for step in deck.steps:
        if step.films and step.films[0].op == "NEW":
            current = {}
        for card in step.films:
            rows = _loaded_face_rows(block, order, card, "*FILM", "F")
            current.update({(int(r), card.face): (card.coefficient, card.sink) for r in rows})
        per_step.append(dict(current))
    keys = sorted(set().union(*per_step)) if per_step else []
    values = [
        tuple(np.array([film.get(k, (0.0, 0.0))[i] for k in keys]) for i in (0, 1))
        for film in per_step
    ]
    return np.array(keys, dtype=np.int64).reshape(-1, 2), values


def _check_face(face: int, block: ElementBlock, location: object, card: str, letter: str) -> None:
    """Raise ``ValueError`` naming the line if ``face`` is not a face of the block's elements."""
    count = len(block.type.faces)
    if face > count:
        raise ValueError(
            f"{location}: {card} {letter}{face}: {block.type.name} elements have faces "
            f"{letter}1..{letter}{count}"
        )


def _check_heat_boundaries(deck: Deck) -> None:
    """Refuse prescribed displacements other than 0 in a deck of ``*HEAT TRANSFER`` steps.

    ccx 2.20 prints their values as U without solving the mechanics (measured); the runner's
    displacement stays 0 (docs/method.md §20.9).
    """
    cards = [*deck.boundaries, *(b for step in deck.steps for b in step.boundaries)]
    for b in cards:
        if b.value != 0.0:
            raise NotImplementedError(
                f"{b.location}: a prescribed displacement ({b.value}) in a *HEAT TRANSFER deck "
                "is not supported yet (the mechanics is not solved; ccx prints the value as U)"
            )


def _check_boundary(b: Boundary) -> None:
    if b.amplitude is not None:
        raise NotImplementedError(
            f"{b.location}: *BOUNDARY dof 11 with an AMPLITUDE is not supported yet (temperatures "
            "are applied at once at the step start, as ccx does without one)"
        )


def thermal_model(
    deck: Deck,
    block: ElementBlock,
    mesh: dolfinx.mesh.Mesh,
    degree: int,
    node_dof: np.ndarray,
    element_cell: np.ndarray,
    dx: ufl.Measure,
) -> ThermalModel:
    """The :class:`ThermalModel` of a deck with coupled steps (``is_thermal``).

    Args:
        deck: The deck.
        block: Its element block.
        mesh: The mesh.
        degree: The displacement's degree (the temperature's space is numbered like it).
        node_dof: Local block dof of each deck node (-1 where this process has none).
        element_cell: Local cell of each element row (-1 elsewhere).
        dx: The volume measure with ccx's quadrature.
    """
    Q = compat.scalar_space(mesh, "Lagrange", degree)
    T = dolfinx.fem.Function(Q, name="temperature")
    Q0 = compat.scalar_space(mesh, "DG", 0)
    heat = all(s.coupled.heat for s in deck.steps)  # no thermal strain: C3D8I conducts as C3D8
    conducting = ("C3D8", "C3D8I", "C3D15") if heat else ("C3D8", "C3D15")  # C3D15: §39
    if block.type.name not in conducting:
        procedure = "*HEAT TRANSFER" if heat else "*COUPLED TEMPERATURE-DISPLACEMENT"
        raise NotImplementedError(
            f"{block.locations[0]}: {procedure} with {block.type.name} elements is not supported "
            "yet (measured against ccx for C3D8 and C3D15 only, and C3D8I in heat transfer)"
        )
    if heat:
        _check_heat_boundaries(deck)
    transient = any(not s.coupled.steady for s in deck.steps)
    for step in deck.steps:
        if step.coupled.deltmx is not None and not step.coupled.steady:
            raise NotImplementedError(
                f"{step.coupled.location}: DELTMX (the largest temperature change per increment) "
                "is not supported yet"
            )
    k = _cell_values(deck, block, element_cell, Q0, "*CONDUCTIVITY", True)
    rho = _cell_values(deck, block, element_cell, Q0, "*DENSITY", transient)
    c = _cell_values(deck, block, element_cell, Q0, "*SPECIFIC HEAT", transient)
    alpha = _cell_values(deck, block, element_cell, Q0, "*EXPANSION", False)
    for condition in deck.initial_temperatures:
        dofs = node_dof[deck.node_index(condition.nodes)]
        T.x.array[dofs[dofs >= 0]] = condition.value
    constraints = wedge_serendipity_constraints(Q) if block.type.name == "C3D15" else []
    _fill_centres(T, constraints)
    T.x.scatter_forward()
    T_old = dolfinx.fem.Function(Q, name="temperature_old")
    T_init = dolfinx.fem.Function(Q, name="initial_temperature")
    T_old.x.array[:] = T_init.x.array[:] = T.x.array
    cell_temperature = CellTemperature(T)
    T_init_c = dolfinx.fem.Function(cell_temperature.T_c.function_space, name="initial_cell_temp")
    T_init_c.x.array[:] = cell_temperature.T_c.x.array
    inverse_dt = dolfinx.fem.Constant(mesh, 0.0)
    v = ufl.TestFunction(Q)
    residual = (
        k * ufl.inner(ufl.grad(T), ufl.grad(v)) * dx + inverse_dt * rho * c * (T - T_old) * v * dx
    )
    conductances = []
    for pair in deck.contact_pairs:
        rows = deck.interactions[pair.interaction].extra.get("*GAP CONDUCTANCE")
        conductances.append(_conductance(rows, pair.interaction))
    nodes, per_step = _bc_nodes(deck)
    dofs = node_dof[deck.node_index(nodes)] if nodes.size else np.zeros(0, np.int64)
    held = dofs >= 0
    bc_dofs = dofs[held].astype(np.int32)
    bc_values = [np.array([values[n] for n in nodes.tolist()])[held] for values in per_step]
    bc_value = dolfinx.fem.Function(Q, name="prescribed_temperature")
    bcs = [dolfinx.fem.dirichletbc(bc_value, bc_dofs)]
    flux_held = node_dof >= 0
    flux_values = [flows[flux_held] for flows in _nodal_flows(deck, block)]
    flux = dolfinx.fem.Function(Q, name="nodal_heat_flow")
    film_keys, film_values = _film_faces(deck, block)
    films = []
    if film_keys.size:
        films = c3d15_films(deck, block, T, node_dof, element_cell, film_keys, bc_dofs)
    return ThermalModel(Q, T, T_old, T_init, cell_temperature, T_init_c, inverse_dt, alpha, k,
                        residual, conductances, bc_dofs, bc_values, bc_value, bcs,
                        constraints, flux, node_dof[flux_held].astype(np.int32), flux_values,
                        films, film_values,
                        strain_at_points=block.type.name == "C3D15")  # fmt: skip


def _conductance(rows: tuple | None, interaction: str) -> GapConductance:
    """The ``*GAP CONDUCTANCE`` table of an interaction (zero without the card)."""
    if rows is None:
        return GapConductance.constant(0.0)
    table = [tuple(0.0 if x is None else x for x in (*r, None, None)[:3]) for r in rows]
    try:
        return GapConductance.from_rows(table)
    except ValueError as error:
        raise ValueError(
            f"*GAP CONDUCTANCE of *SURFACE INTERACTION {interaction}: {error}"
        ) from None
