"""Checks once the whole deck is read, and the assembly of the ``Deck``."""

from __future__ import annotations

import dataclasses

import numpy as np

from ..elements import ELEMENT_TYPES, frozen_array
from .data import (
    NODE_TWIN,
    Deck,
    ElementBlock,
    Material,
    SolidSection,
    SurfaceInteraction,
)
from .errors import DeckError, Location
from .materials import table_at_temperature
from .state import MaterialBuilder, ReaderState
from .wedges import C3D6_AS_C3D8, check_wedge_orientation, wedge_faces, wedge_rotations

#: Material cards of ``(value, temperature)`` lines resolved or refused like ``*ELASTIC`` tables
#: (``Checks._material_data``).
_TEMPERATURE_TABLES = ("*DENSITY", "*EXPANSION", "*CONDUCTIVITY", "*SPECIFIC HEAT")


class Checks(ReaderState):
    """Cross-references, numbering and completeness checks; builds the ``Deck``."""

    def _finish(self) -> Deck:
        shells = self._expand_shells()  # ShellCards (shells.py): S8 -> C3D20 bricks
        node_ids, node_coords = self._assemble_nodes()
        rotation = self._collapse_wedges()
        elements = self._assemble_elements()
        all_elements = (
            np.sort(np.concatenate([b.ids for b in elements.values()]))
            if elements
            else np.zeros(0, np.int64)
        )
        for block in elements.values():
            self._check_known(node_ids, block.connectivity, "node", "element connectivity",
                              block.locations)  # fmt: skip
        self._check_refs(node_ids, self.node_refs, "node")
        self._apply_transforms(node_ids, node_coords)  # TransformCards: *BOUNDARY in global dofs
        springs = self._finish_springs(all_elements)
        known_elements = np.sort(np.concatenate([all_elements, *(s.ids for s in springs)]))
        self._check_refs(known_elements, self.element_refs, "element")
        wedges = self._check_wedges(elements, node_ids, node_coords, rotation)
        self._check_faces(elements)
        materials = self._check_materials(elements, all_elements)
        interactions = self._check_contact()
        for step in self.steps:
            for load in step.dloads:
                if np.any(np.isin(load.elements, wedges)):
                    raise DeckError("*DLOAD on a C3D6 element is not supported", load.location)
                self._check_face_numbers(elements, load.elements, load.face, load.location)
            for change in step.model_changes:
                if change.slave + NODE_TWIN in self.surfaces:
                    raise DeckError(
                        f"*MODEL CHANGE of a contact pair whose slave {change.slave} names a node "
                        "and an element surface is not supported",
                        change.location,
                    )
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
            nsets={k: frozen_array(v, np.int64) for k, v in self.nsets.items()},
            elsets={k: frozen_array(v, np.int64) for k, v in self.elsets.items()},
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
            springs=springs,
            ties=tuple(self.ties.values()),
            cyclic_symmetries=tuple(self.cyclic_symmetries),
            initial_temperatures=tuple(self.initial_temperatures),
            temperature_boundaries=tuple(self.temperature_boundaries),
            shells=shells,
            transformed_nodes=self._transformed_nodes(),
            time_points=dict(self.time_points),
            wedges=wedges,
            wedge_nodes=self._wedge_nodes(),
        )

    def _collapse_wedges(self) -> np.ndarray:
        """Append the C3D6 elements to the C3D8 rows, turned and collapsed (``wedges.py``).

        Returns each wedge's rotation, in the order of ``wedge_ids``.
        """
        if not self.wedge_ids:
            return np.zeros(0, np.int64)
        ids = np.asarray(self.wedge_ids, np.int64)
        rows = np.asarray(self.wedge_rows, np.int64)
        rotation = wedge_rotations(ids, rows, tuple(self.wedge_locs))
        turn = (np.arange(3)[None, :] + rotation[:, None]) % 3
        turned = np.take_along_axis(rows, np.hstack([turn, 3 + turn]), axis=1)
        self.element_ids["C3D8"].extend(self.wedge_ids)
        self.element_rows["C3D8"].extend(turned[:, C3D6_AS_C3D8].tolist())
        self.element_locs["C3D8"].extend(self.wedge_locs)
        return rotation

    def _wedge_nodes(self) -> np.ndarray:
        """The wedges' nodes as read, rows by ascending element number (``Deck.wedge_nodes``)."""
        rows = np.asarray(self.wedge_rows, np.int64).reshape(-1, 6)
        return frozen_array(rows[np.argsort(np.asarray(self.wedge_ids, np.int64))], np.int64)

    def _check_wedges(self, elements: dict[str, ElementBlock], node_ids: np.ndarray,
                      node_coords: np.ndarray, rotation: np.ndarray) -> np.ndarray:  # fmt: skip
        """Check the C3D6 elements' orientation and give their surface faces C3D8 numbers.

        Returns the sorted wedge numbers (docs/method.md §30).
        """
        ids = np.asarray(self.wedge_ids, np.int64)
        order = np.argsort(ids)
        wedges = frozen_array(ids[order], np.int64)
        if wedges.size == 0:
            return wedges
        block = elements["C3D8"]
        rows = np.flatnonzero(np.isin(block.ids, wedges))
        coords = node_coords[np.searchsorted(node_ids, block.connectivity[rows])]
        check_wedge_orientation(block.ids[rows], coords, tuple(block.locations[k] for k in rows))
        for name, surface in self.surfaces.items():
            if surface.type != "ELEMENT":
                continue
            position = np.minimum(np.searchsorted(wedges, surface.elements), wedges.size - 1)
            hit = wedges[position] == surface.elements
            turn = np.where(hit, rotation[order][position], -1)
            faces = wedge_faces(surface.faces, turn, f"surface {name}", surface.location)
            if faces is not surface.faces:
                self.surfaces[name] = dataclasses.replace(
                    surface, faces=frozen_array(faces, np.int64)
                )
        return wedges

    def _transformed_nodes(self) -> np.ndarray:
        """Sorted numbers of the nodes of every ``*TRANSFORM`` card."""
        sets = [np.asarray(self.nsets[t.nset], np.int64) for t in self.transforms]
        return frozen_array(np.unique(np.concatenate([np.zeros(0, np.int64), *sets])), np.int64)

    def _split_overridden_sections(self, owner: dict[int, SolidSection]) -> None:
        """Give a section whose elements a later section takes the rest only (docs/method.md §28.1).

        ccx 2.20 lets a later ``*SOLID SECTION`` hold an element of an earlier one (measured on
        metalforming); the earlier section gets the element set ``<ELSET>#<k>`` of the elements
        it keeps, so that the sections the model sees are disjoint.
        """
        sections = []
        for k, section in enumerate(self.sections):
            members = np.asarray(self.elsets[section.elset], np.int64)
            kept = np.array([e for e in members.tolist() if owner[e] is section], np.int64)
            if kept.size != np.unique(members).size:
                name = f"{section.elset}#{k + 1}"
                self.elsets[name] = kept.tolist()
                section = dataclasses.replace(section, elset=name)
            sections.append(section)
        self.sections = sections

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
            repeated = np.any(ordered[:, 1:] == ordered[:, :-1], axis=1)
            repeats = np.flatnonzero(repeated & ~np.isin(ids, self.wedge_ids))  # read checked
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
        # ``known`` is sorted: a binary search, not np.isin's sort per call (one per *BOUNDARY line)
        pos = np.minimum(np.searchsorted(known, ids), max(known.size - 1, 0))
        ok = known[pos] == ids if known.size else np.zeros(ids.shape, dtype=bool)
        if np.all(ok):
            return
        bad = np.argwhere(~ok)[0]
        loc = locations[bad[0]] if len(locations) > 1 else locations[0]
        number = int(ids[tuple(bad)])
        raise DeckError(f"{what} refers to {kind} {number}, which is not defined", loc)

    @classmethod
    def _check_refs(cls, known: np.ndarray, refs: list[tuple[str, np.ndarray, Location]],
                    kind: str) -> None:  # fmt: skip
        """:meth:`_check_known` of every card's references at once (a deck has thousands).

        The error is the loop's: the first reference (in deck order) to an undefined number.
        """
        if not refs:
            return
        ids = np.concatenate([np.ravel(r[1]).astype(np.int64, copy=False) for r in refs])
        pos = np.minimum(np.searchsorted(known, ids), max(known.size - 1, 0))
        if known.size and np.array_equal(known[pos], ids):
            return
        for what, ref_ids, loc in refs:  # only on a bad deck: name the first bad reference
            cls._check_known(known, ref_ids, kind, what, (loc,))

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
                owner[element] = section  # a later section holds, as in ccx 2.20 (measured)
        self._split_overridden_sections(owner)
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
            name: Material(
                m.name,
                self._elastic_constants(m),
                self._material_data(m),
                m.location,
                m.plastic,
                m.plastic_location,
            )
            for name, m in self.materials.items()
        }

    def _elastic_constants(self, material: MaterialBuilder) -> tuple[float, float] | None:
        """``(E, nu)`` of a material: its ``*ELASTIC`` table at the deck's one temperature."""
        rows = material.elastic_rows
        if len(rows) <= 1:
            return material.elastic
        temperature = self._one_temperature("*ELASTIC", material, material.elastic_row_locations)
        if temperature is None:
            return rows[0][:2]
        young, nu = table_at_temperature(rows, temperature)
        return young, nu

    def _material_data(self, material: MaterialBuilder) -> dict:
        """The material's other cards, a ``*DENSITY`` table at the deck's one temperature.

        A ``*DENSITY`` table in a deck whose temperatures do not change holds at its one
        temperature, as ``*ELASTIC`` (measured on eigenvalues, docs/method.md §41.2); in other
        decks it stays as read (the mass refuses it where it is used). ``*EXPANSION``,
        ``*CONDUCTIVITY`` and ``*SPECIFIC HEAT`` tables are refused at their second line in
        decks with coupled or heat transfer steps (which use them), left as read elsewhere.
        """
        extra = dict(material.extra)
        thermal = any(s.coupled is not None for s in self.steps)
        for card in _TEMPERATURE_TABLES:
            rows = extra.get(card)
            if rows is None or len(rows) <= 1:
                continue
            locations = material.extra_locations[card]
            if card != "*DENSITY":
                if thermal:
                    self._one_temperature(card, material, locations)  # refuses
                continue
            if self._temperatures_change():
                continue
            for row, loc in zip(rows, locations):
                if len(row) != 2 or row[0] is None or row[1] is None:
                    raise DeckError(
                        f"{card} with several data lines: a value and a temperature on each", loc
                    )
            for row, before, loc in zip(rows[1:], rows, locations[1:]):
                if row[1] <= before[1]:
                    raise DeckError(
                        f"{card}: the temperatures must increase, {row[1]} follows {before[1]}",
                        loc,
                    )
            temperature = self._one_temperature(card, material, locations)
            value = (
                rows[0][0] if temperature is None else table_at_temperature(rows, temperature)[0]
            )
            extra[card] = ((value,),)
        return extra

    def _temperatures_change(self) -> bool:
        """Whether the deck's temperatures change (thermal steps, ``*TEMPERATURE``, dof 11)."""
        return bool(self.temperature_boundaries) or any(
            s.coupled is not None or s.temperatures or s.temperature_fields for s in self.steps
        )

    def _one_temperature(
        self, card: str, material: MaterialBuilder, locations: tuple[Location, ...]
    ) -> float | None:
        """The one temperature at which a material table holds for the whole run.

        ccx 2.20 (measured, docs/method.md §41.2): without any temperature in the deck a
        table's first line holds (None); with one initial temperature everywhere the table is
        interpolated there. Temperatures that vary in space or in time are refused at the
        table's second line.
        """
        if self._temperatures_change():
            raise DeckError(
                f"temperature-dependent {card} of material {material.name} (several data "
                "lines) in a deck whose temperatures change (coupled or heat transfer steps, "
                "*TEMPERATURE, temperature *BOUNDARY) is not supported yet",
                locations[1],
            )
        if not self.initial_temperatures:
            return None
        values = {t.value for t in self.initial_temperatures}
        given = np.unique(np.concatenate([t.nodes for t in self.initial_temperatures]))
        if len(values) > 1 or not np.all(np.isin(np.asarray(self.node_ids), given)):
            raise DeckError(
                f"temperature-dependent {card} of material {material.name} (several data "
                "lines) needs one initial temperature at every node (*INITIAL CONDITIONS, "
                "TYPE=TEMPERATURE); varying temperatures are not supported yet",
                locations[1],
            )
        return values.pop()

    def _check_contact(self) -> dict[str, SurfaceInteraction]:
        self.contact_pairs = [
            dataclasses.replace(pair, slave=pair.slave + NODE_TWIN)
            if pair.slave + NODE_TWIN in self.surfaces
            else pair
            for pair in self.contact_pairs
        ]  # ccx's slave: the node surface of a name that also has faces (docs/method.md §30)
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
            name: SurfaceInteraction(
                i.name, i.behavior, i.friction, dict(i.extra), i.location, i.damping
            )
            for name, i in self.interactions.items()
        }
