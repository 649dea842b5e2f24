"""Loads and prescribed displacements of every step with ccx's rules.

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

``*DLOAD`` faces with the same history in every step share one pressure Constant (a group).
``*DLOAD ... GRAV`` lines (docs/method.md §27) follow the same rules per element and component of
the acceleration; repeated lines on an element add up, and their OP is the step's ``*DLOAD`` OP.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

import dolfinx.mesh

from dolfinx_ntf import compat

from ..deck import Deck, Step
from .c3d15 import C3D15Pressures
from .mesh import MeshMaps, element_faces_to_facets, exterior

__all__ = [
    "Schedule",
    "ScheduleBuilder",
    "StepLoads",
    "amplitude_index",
    "end_values",
    "schedules",
    "step_times",
]


@dataclass(eq=False)
class Schedule:
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
        bc: Prescribed-value history; ``bc.start`` is filled by
            :meth:`~dolfinx_ntf.calculix.model.calculix_model.CalculixModel.begin_step`.
        reference_keys: ``(R,)`` keys ``3 node row + component`` of the prescribed components of
            nodes in no element (reference nodes of ``*EQUATION``); ``reference`` their history,
            from their value at the end of the previous step; ``reference_force_keys`` and
            ``reference_force`` likewise for their ``*CLOAD`` forces.
        gravity_keys: ``(G,)`` keys ``3 local cell + component`` of the ``GRAV`` accelerations
            on this process's cells (owned and ghost); ``gravity`` their history.
    """

    step: Step
    total_time_start: float
    cload_dofs: np.ndarray
    cload: Schedule
    pressure: Schedule
    bc_dofs: np.ndarray
    bc: Schedule
    reference_keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    reference: Schedule | None = None
    reference_force_keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    reference_force: Schedule | None = None
    gravity_keys: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    gravity: Schedule | None = None

    @property
    def period(self) -> float:
        """Step time period."""
        return self.step.static.period


class ScheduleBuilder:
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
        """Start a step: step-time amplitudes end, ``new`` (``OP=NEW``) removes all values."""
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
        """A card of the step: ``value`` at ``keys`` (added or replacing), with ``amplitude``."""
        if self.add:
            fresh = keys[~self._touched[keys]]
            self.ref[fresh] = 0.0
            np.add.at(self.ref, keys, value)
        else:
            self.ref[keys] = value
        self._touched[keys] = True
        self.active[keys] = True
        self.amplitude[keys] = amplitude

    def finish(self, evaluate_end: Callable[[Schedule], np.ndarray]) -> Schedule:
        """The step's schedule; ``evaluate_end`` gives its values at the end of the step."""
        schedule = Schedule(self.end.copy(), self.ref.copy(), self.amplitude.copy())
        self.end = evaluate_end(schedule)
        return schedule


def amplitude_index(deck: Deck, names: list[str], name: str | None) -> int:
    """Index of amplitude ``name`` in ``names``, -1 for none."""
    return -1 if name is None else names.index(name)


def end_values(
    deck: Deck, names: list[str], schedule: Schedule, period: float, total_end: float
) -> np.ndarray:
    """Values of ``schedule`` at the end of a step of ``period`` ending at ``total_end``."""
    value = schedule.ref.copy()
    for index in np.unique(schedule.amplitude[schedule.amplitude >= 0]):
        amp = deck.amplitudes[names[index]]
        mask = schedule.amplitude == index
        value[mask] = schedule.ref[mask] * np.interp(
            total_end if amp.total_time else period, amp.times, amp.values
        )
    return value


def step_times(deck: Deck) -> list[float]:
    """Total time at the start of every step (``TOTAL TIME AT START``, ``TIME RESET``).

    A ``*FREQUENCY`` step takes no time: ccx 2.20 prints its modes at its start plus 1 (its
    default period) but starts the next step where the frequency step started (measured with a
    static and with a ``*MODAL DYNAMIC`` step after it, docs/method.md §25.3).
    """
    starts, total = [], 0.0
    for step in deck.steps:
        static = step.static
        if static.total_time_at_start is not None:
            total = static.total_time_at_start
        elif static.time_reset:
            total -= static.period
        starts.append(total)
        if step.frequency is None:
            total += static.period
    return starts


def schedules(
    deck: Deck, maps: MeshMaps, mesh: dolfinx.mesh.Mesh
) -> tuple[list[StepLoads], list[str], compat.MeshTags | C3D15Pressures | None, int]:
    """Per-step schedules of forces, pressures (grouped) and prescribed displacements.

    Dofs are this process's; nodes in no element (``maps.meshed`` false) are references.
    Returns the schedule of every step, the amplitude names by index, the facet tags of the
    pressure groups (value ``group + 1``; C3D15: the faces and their groups instead,
    docs/method.md §34.4) and the number of groups.
    """
    block, node_dof = maps.block, maps.node_dof
    names = list(deck.amplitudes)
    amp_total = np.array([deck.amplitudes[n].total_time for n in names] + [False], dtype=bool)
    num_nodes = deck.node_ids.size
    cload = ScheduleBuilder(3 * num_nodes, amp_total, add_within_step=True)
    dload = ScheduleBuilder(6 * block.ids.size, amp_total, add_within_step=True)
    bound = ScheduleBuilder(3 * num_nodes, amp_total, add_within_step=False)
    grav = ScheduleBuilder(3 * block.ids.size, amp_total, add_within_step=True)
    order = np.argsort(block.ids)
    starts = step_times(deck)
    raw = []
    gravity: list[Schedule] = []
    for s, step in enumerate(deck.steps):
        period = step.static.period
        total_end = starts[s] + period

        def end(schedule, period=period, total_end=total_end):
            return end_values(deck, names, schedule, period, total_end)

        cards = (list(deck.boundaries) if s == 0 else []) + list(step.boundaries)
        bound.begin(new=bool(step.boundaries) and step.boundary_op == "NEW")
        for card in cards:
            keys = (
                3 * deck.node_index(card.nodes)[:, None]
                + np.arange(card.first_dof - 1, card.last_dof)
            ).ravel()
            bound.card(keys, card.value, amplitude_index(deck, names, card.amplitude))
        bc = bound.finish(end)
        bc_active = bound.active.copy()

        cload.begin(new=step.cload_op == "NEW" and bool(step.cloads))
        for card in step.cloads:
            cload.card(
                3 * deck.node_index(card.nodes) + card.dof - 1,
                card.value,
                amplitude_index(deck, names, card.amplitude),
            )
        forces = cload.finish(end)

        dload.begin(new=step.dload_op == "NEW" and bool(step.dloads))
        for card in step.dloads:
            rows = order[np.searchsorted(block.ids, card.elements, sorter=order)]
            dload.card(
                6 * rows + card.face - 1, card.value, amplitude_index(deck, names, card.amplitude)
            )
        pressures = dload.finish(end)

        grav.begin(new=step.dload_op == "NEW" and bool(step.dloads or step.gravity))
        for card in step.gravity:
            rows = order[np.searchsorted(block.ids, np.unique(card.elements), sorter=order)]
            for k in range(3):
                if card.direction[k] != 0.0:
                    grav.card(3 * rows + k, card.value * card.direction[k],
                              amplitude_index(deck, names, card.amplitude))  # fmt: skip
        gravity.append(grav.finish(end))
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
    pressure_tags: compat.MeshTags | C3D15Pressures | None = None
    if keys.size and block.type.name == "C3D15":  # nodal forces: no ds on prisms (§34)
        pressure_tags = C3D15Pressures(keys, group, int(unique.shape[0]))
    elif keys.size:
        facets, _ = element_faces_to_facets(
            deck, maps, block.ids[keys // 6], keys % 6 + 1, "*DLOAD", deck.path
        )
        inner = facets >= 0  # a process without cells has no facet to look at
        inner[inner] = ~exterior(mesh, facets[inner])
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
    cell_keys = 3 * np.repeat(maps.element_cell, 3) + np.tile(np.arange(3), block.ids.size)
    for s, (step, (bc, bc_active, forces, pressure)) in enumerate(zip(deck.steps, raw)):
        accelerated = ((gravity[s].ref != 0) | (gravity[s].start != 0)) & (cell_keys >= 0)
        gdim = block.type.tdim  # 2D elements: no z dofs (their z conditions are checked, §23)
        component = np.tile(np.arange(3), num_nodes)
        dofs3 = gdim * np.repeat(node_dof, 3) + component  # unrolled dof of each key
        local = np.repeat(node_dof >= 0, 3) & (component < gdim)
        valid = np.repeat(maps.meshed, 3)
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
                cload=Schedule(forces.start[f_keys], forces.ref[f_keys], forces.amplitude[f_keys]),
                pressure=Schedule(
                    group_history[:, 0].copy(),
                    group_history[:, 1].copy(),
                    group_history[:, 2].astype(np.int64),
                ),
                bc_dofs=bc_dofs,
                bc=Schedule(np.zeros(bc_dofs.size), bc.ref[bc_keys], bc.amplitude[bc_keys]),
                reference_force_keys=np.flatnonzero(loaded & ~valid),
                reference_force=Schedule(
                    forces.start[loaded & ~valid],
                    forces.ref[loaded & ~valid],
                    forces.amplitude[loaded & ~valid],
                ),
                gravity_keys=cell_keys[accelerated],
                gravity=Schedule(
                    gravity[s].start[accelerated],
                    gravity[s].ref[accelerated],
                    gravity[s].amplitude[accelerated],
                ),
                reference_keys=np.flatnonzero(bc_active & ~valid),
                reference=Schedule(
                    bc.start[bc_active & ~valid],
                    bc.ref[bc_active & ~valid],
                    bc.amplitude[bc_active & ~valid],
                ),
            )
        )
    return steps, names, pressure_tags, int(unique.shape[0])
