"""Shell cards: S8/S8R/S4 elements and ``*SHELL SECTION``, expanded into C3D20/C3D20R/C3D8I bricks.

See docs/method.md §24. The shells are read as written; once the deck is read,
``_expand_shells`` replaces them by the bricks ccx 2.20 makes of them
(``shell_expansion.expand_shells``: new nodes through the thickness, a S8 becomes a C3D20 and a
S8R a C3D20R, keeping its element number), gives the bricks the shell section's material, and
carries the boundary conditions of the shell nodes to the expanded nodes as ccx does: a dof 1-3
of a corner node to its middle node plus the equation bottom + top - 2 middle = 0, of a midside
node (value 0 only) as the equation bottom + top = 0; dofs 1-6 all fixed to 0: the middle node
fixed and bottom and top moving only symmetrically along the normal (a fixed knot that keeps its
uniform expansion, as ccx 2.20's results show).
Everything else on a shell node (other rotational conditions, loads, velocities, equations,
contact slave nodes, RF output) is refused: ccx's treatment was not measured.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..elements import frozen_array
from ..shell_expansion import ShellExpansion, expand_shells
from .data import Boundary, Equation, SolidSection
from .errors import DeckError, Location
from .lexer import Card
from .state import ReaderState

#: The brick ccx makes of each shell type (ccx manual: S8 -> C3D20, S8R -> C3D20R; checked by
#: the number of integration points ccx 2.20 prints).
SHELL_TYPES = {"S8": "C3D20", "S8R": "C3D20R", "S4": "C3D8I"}

#: Nodes per shell element.
SHELL_NODES = {"S8": 8, "S8R": 8, "S4": 4}

#: Face labels of shell elements: the brick's bottom (SNEG, on the side of -n) and top (SPOS).
SHELL_FACES = {"SNEG": 1, "SPOS": 2}


@dataclasses.dataclass(frozen=True, eq=False)
class ShellSection:
    """A ``*SHELL SECTION``: material, thickness and offset (units of thickness) of ``elset``."""

    elset: str
    material: str
    thickness: float
    offset: float
    location: Location


class ShellCards(ReaderState):
    """Handlers of the shell cards and the expansion once the deck is read."""

    def _shell_elements(self, card: Card, type_name: str) -> None:
        """The ``*ELEMENT, TYPE=S8`` (S8R, S4) data lines: element number and its nodes."""
        needed = SHELL_NODES[type_name] + 1
        tokens: list[str] = []
        start: Location | None = None
        ids: list[int] = []
        for fields, _, loc in card.lines:
            if not tokens:
                start = loc
            tokens.extend(f for f in fields if f != "")
            if len(tokens) < needed:
                continue
            if len(tokens) > needed or start is None:
                raise DeckError(
                    f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has "
                    f"{needed - 1}",
                    start,
                )
            numbers = [self._int(t, "element or node number", start) for t in tokens]
            self.shell_rows.append((type_name, numbers[0], numbers[1:], start))
            ids.append(numbers[0])
            tokens = []
        if tokens:
            raise DeckError(
                f"element {tokens[0]} has {len(tokens) - 1} nodes, {type_name} has {needed - 1}",
                start,
            )
        self.element_refs.append((card.name, np.array(ids, np.int64), card.location))
        if card.params.get("ELSET"):
            self.elsets.setdefault(card.params["ELSET"] or "", []).extend(ids)
            self.set_locations.setdefault(("element", card.params["ELSET"] or ""), card.location)

    def _k_SHELLSECTION(self, card: Card) -> None:
        self._check_params(
            card, allowed={"ELSET", "MATERIAL", "OFFSET"}, required={"ELSET", "MATERIAL"}
        )
        elset = card.params["ELSET"] or ""
        if elset not in self.elsets:
            raise DeckError(f"element set {elset} is not defined (before this line)", card.location)
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(card.lines) > 1 or not fields or fields[0] == "":
            raise DeckError("*SHELL SECTION data line: thickness (one line)", loc)
        thickness = self._float(fields[0], "shell thickness", loc)
        if thickness <= 0:
            raise DeckError(f"*SHELL SECTION: thickness must be > 0, got {thickness:g}", loc)
        offset = self._float(card.params.get("OFFSET") or "0", "OFFSET", card.location)
        self.shell_sections.append(
            ShellSection(elset, card.params["MATERIAL"] or "", thickness, offset, card.location)
        )

    def _expand_shells(self) -> ShellExpansion | None:
        """Replace the shells by their bricks (nodes, elements, sections, boundaries).

        None without shells. Refuses what cannot be carried to the bricks.
        """
        rotational = [b for b in self._all_boundaries() if b.last_dof > 3]
        if not self.shell_rows:
            if rotational:
                raise DeckError(
                    f"degree of freedom {rotational[0].last_dof} is not supported (solid "
                    "elements have dofs 1, 2, 3)",
                    rotational[0].location,
                )
            if self.shell_face_refs:
                raise DeckError(
                    "face labels SPOS and SNEG belong to shell elements (S8, S8R, S4)",
                    self.shell_face_refs[0][1],
                )
            return None
        types = [row[0] for row in self.shell_rows]
        widths = {SHELL_NODES[t] for t in types}
        if len(widths) > 1:
            k = next(i for i, t in enumerate(types) if SHELL_NODES[t] != SHELL_NODES[types[0]])
            raise DeckError(
                f"shell element {self.shell_rows[k][1]} ({types[k]}) and element "
                f"{self.shell_rows[0][1]} ({types[0]}): S4 and S8 shells in one deck are not "
                "supported",
                self.shell_rows[k][3],
            )
        ids = np.array([row[1] for row in self.shell_rows], np.int64)
        conn = np.array([row[2] for row in self.shell_rows], np.int64)
        locs = [row[3] for row in self.shell_rows]
        thickness, offset = self._shell_thickness(ids, locs)
        node_ids = np.array(self.node_ids, np.int64)
        order = np.argsort(node_ids, kind="stable")
        coords = np.array(self.node_coords, np.float64).reshape(-1, 3)[order]
        missing = ~np.isin(conn, node_ids)
        if missing.any():
            k = int(np.argwhere(missing)[0, 0])
            node = int(conn[missing][0])
            raise DeckError(f"node {node} of element connectivity is not defined", locs[k])
        try:
            new_ids, new_coords, bricks, expansion = expand_shells(
                conn, node_ids[order], coords, thickness, offset, ids
            )
        except ValueError as error:
            raise DeckError(str(error), locs[0]) from None
        for face_ids, loc in self.shell_face_refs:
            solid = face_ids[~np.isin(face_ids, ids)]
            if solid.size:
                raise DeckError(
                    f"face label SPOS/SNEG on element {int(solid[0])}, which is not a shell", loc
                )
        self.node_ids.extend(new_ids.tolist())
        self.node_coords.extend(map(tuple, new_coords))
        self.node_locs.extend(locs[0] for _ in range(new_ids.size))
        for k, name in enumerate(types):
            brick = SHELL_TYPES[name]
            self.element_ids[brick].append(int(ids[k]))
            self.element_rows[brick].append(bricks[k].tolist())
            self.element_locs[brick].append(locs[k])
        self.sections.extend(
            SolidSection(s.elset, s.material, s.location) for s in self.shell_sections
        )
        self._carry_boundaries(expansion)
        self._refuse_on_shell_nodes(expansion)
        return expansion

    def _shell_thickness(self, ids: np.ndarray, locs: list[Location]) -> tuple[np.ndarray, ...]:
        """``(E,)`` thickness and offset of each shell element from its ``*SHELL SECTION``."""
        thickness = np.full(ids.size, np.nan)
        offset = np.zeros(ids.size)
        for section in self.shell_sections:
            members = np.isin(ids, np.array(self.elsets[section.elset], np.int64))
            thickness[members] = section.thickness
            offset[members] = section.offset
        lacking = np.flatnonzero(np.isnan(thickness))
        if lacking.size:
            k = int(lacking[0])
            raise DeckError(f"shell element {int(ids[k])} has no *SHELL SECTION", locs[k])
        return thickness, offset

    def _all_boundaries(self) -> list[Boundary]:
        steps = [b for s in self.steps for b in s.boundaries]
        current = self.step.boundaries if self.step is not None else []
        return [*self.boundaries, *steps, *current]

    def _carry_boundaries(self, expansion: ShellExpansion) -> None:
        """Boundary conditions on shell nodes moved to their expanded nodes (module docstring)."""
        self._tied: set[tuple[int, int]] = set()  # (bottom node, dof) of the equations made
        self._released = any(s.boundary_op == "NEW" for s in self.steps)
        self.boundaries = self._carried(self.boundaries, expansion, model=True)
        self.steps = [
            dataclasses.replace(
                s, boundaries=tuple(self._carried(list(s.boundaries), expansion, model=False))
            )
            for s in self.steps
        ]

    def _carried(
        self, boundaries: list[Boundary], expansion: ShellExpansion, *, model: bool
    ) -> list[Boundary]:
        out: list[Boundary] = []
        for b in boundaries:
            nodes = np.asarray(b.nodes)
            shell = np.isin(nodes, expansion.nodes)
            if not shell.any():
                if b.last_dof > 3:
                    raise DeckError(
                        f"*BOUNDARY: dof {b.last_dof} of node {int(nodes[0])}, which is not a "
                        "shell node (solid elements have dofs 1, 2, 3)",
                        b.location,
                    )
                out.append(b)
                continue
            if (~shell).any():
                out.append(dataclasses.replace(b, nodes=frozen_array(nodes[~shell], np.int64)))
            rows = np.searchsorted(expansion.nodes, nodes[shell])
            expanded = expansion.expanded[rows]
            if b.last_dof > 3:
                if (b.first_dof, b.last_dof, b.value, b.amplitude) != (1, 6, 0.0, None):
                    raise DeckError(
                        f"*BOUNDARY on shell node {int(nodes[shell][0])}: rotational dofs are "
                        "supported only all fixed (dofs 1 to 6, value 0, one line); ccx's other "
                        "treatments (knots, mean rotation equations) are not reproduced",
                        b.location,
                    )
                out.extend(self._fixed_shell_nodes(b, expansion, rows))
                continue
            corner = expansion.corner[rows]
            if not model and self._released:
                raise DeckError(
                    "*BOUNDARY on shell nodes with *BOUNDARY, OP=NEW in a step: the equations "
                    "that carry them to the expanded nodes cannot be released",
                    b.location,
                )
            if corner.any():
                middle = expanded[corner, 1]
                out.append(dataclasses.replace(b, nodes=frozen_array(middle, np.int64)))
            if (~corner).any() and (b.value != 0.0 or b.amplitude is not None):
                raise DeckError(
                    f"*BOUNDARY on the shell node {int(nodes[shell][~corner][0])} (an S8 "
                    "midside or S4 node, no middle node): supported with value 0 only (ccx ties "
                    "the mean of its bottom and top nodes; a prescribed mean is not reproduced)",
                    b.location,
                )
            for (bottom, middle, top), at_corner in zip(expanded, corner):
                for dof in range(b.first_dof, b.last_dof + 1):
                    if (bottom, dof) in self._tied:
                        continue
                    self._tied.add((bottom, dof))
                    terms = [bottom, top, middle] if at_corner else [bottom, top]
                    self.equations.append(Equation(
                        frozen_array(terms, np.int64),
                        frozen_array([dof] * len(terms), np.int64),
                        frozen_array([1.0, 1.0, -2.0][: len(terms)], np.float64),
                        b.location,
                    ))  # fmt: skip
        return out

    def _fixed_shell_nodes(
        self, b: Boundary, expansion: ShellExpansion, rows: np.ndarray
    ) -> list[Boundary]:
        """Dofs 1-6 fixed: middle node fixed, bottom and top move only symmetrically along n.

        ccx's fixed knot keeps its uniform expansion free (measured, docs/method.md §24).
        Equations bottom + top = 0 per dof, and the top node fixed in the two coordinate
        directions across the normal (normals along a coordinate axis only).
        """
        normals = expansion.normals[rows]
        axis = np.argmax(np.abs(normals), axis=1)
        tilted = np.flatnonzero(np.abs(normals[np.arange(axis.size), axis]) < 1.0 - 1e-12)
        if tilted.size:
            raise DeckError(
                f"*BOUNDARY, dofs 1 to 6 on shell node {int(expansion.nodes[rows[tilted[0]]])}: "
                "supported where the shell normal is along a coordinate axis only",
                b.location,
            )
        expanded = expansion.expanded[rows]
        corner = expansion.corner[rows]
        fixed = [dataclasses.replace(b, nodes=frozen_array(expanded[corner, 1], np.int64),
                                     last_dof=3)]  # fmt: skip
        for (bottom, _, top), normal_axis in zip(expanded, axis):
            for dof in (1, 2, 3):
                if (bottom, dof) not in self._tied:
                    self._tied.add((bottom, dof))
                    self.equations.append(Equation(
                        frozen_array([bottom, top], np.int64), frozen_array([dof, dof], np.int64),
                        frozen_array([1.0, 1.0], np.float64), b.location,
                    ))  # fmt: skip
                if dof != normal_axis + 1:
                    fixed.append(dataclasses.replace(
                        b, nodes=frozen_array([top], np.int64), first_dof=dof, last_dof=dof
                    ))  # fmt: skip
        return fixed

    def _refuse_on_shell_nodes(self, expansion: ShellExpansion) -> None:
        """Refuse the references to shell nodes whose treatment by ccx was not measured."""
        named: list[tuple[str, np.ndarray, Location]] = [
            ("*CLOAD", c.nodes, c.location) for s in self.steps for c in s.cloads
        ]
        named += [("*INITIAL CONDITIONS", v.nodes, v.location) for v in self.initial_velocities]
        named += [("*INITIAL CONDITIONS", v.nodes, v.location) for v in self.initial_temperatures]
        named += [("*BOUNDARY, dof 11", b.nodes, b.location) for b in self.temperature_boundaries]
        named += [("*BOUNDARY, dof 11", b.nodes, b.location)
                  for s in self.steps for b in s.temperatures]  # fmt: skip
        named += [("*EQUATION", e.nodes, e.location) for e in self.equations
                  if not np.isin(e.nodes, expansion.expanded).all()]  # fmt: skip
        named += [
            (f"*SURFACE {s.name}, TYPE=NODE", s.nodes, s.location)
            for s in self.surfaces.values()
            if s.type == "NODE"
        ]
        for s in self.steps:
            for p in s.prints:
                if p.kind == "NODE" and "RF" in p.keys and p.set in self.nsets:
                    named.append(("*NODE PRINT, RF", np.array(self.nsets[p.set]), p.location))
        for what, nodes, loc in named:
            hit = np.asarray(nodes)[np.isin(nodes, expansion.nodes)]
            if hit.size:
                raise DeckError(
                    f"{what} names the shell node {int(hit[0])}: not supported on shell nodes "
                    "(ccx's treatment of the expanded nodes is not reproduced)",
                    loc,
                )
