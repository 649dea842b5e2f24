"""``*TRANSFORM``: local directions of nodes, and the ``*BOUNDARY`` lines written in them.

docs/method.md §28. ``TYPE=R`` (rectangular: point a on the local x axis, point b in the local
x-y plane) or ``TYPE=C`` (cylindrical: a and b on the axis; local 1 radial, 2 circumferential,
3 axial, at each node; on the axis local 3 is still the axis, §30.4). The reader rewrites the
``*BOUNDARY`` lines of transformed nodes in global terms: a local direction along a global axis
becomes that global dof (its value times the direction's sign); the zero-valued local directions
of a node in the model definition become linear equations (``*EQUATION`` terms, reduced per node
so that each has its own dependent dof, one-term rows becoming global ``*BOUNDARY`` lines). Other
cases are refused: nonzero values along directions that are not global axes, step
``*BOUNDARY`` lines along such directions, and ``*CLOAD``, ``*EQUATION`` and initial velocities on
transformed nodes.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..elements import frozen_array
from .data import Boundary, Equation
from .errors import DeckError, Location
from .lexer import Card
from .state import ReaderState

__all__ = ["ON_AXIS", "Transform", "TransformCards", "axis_normal", "local_directions"]

#: A local direction whose largest global component exceeds 1 - ALIGNED is that global axis.
ALIGNED = 1e-12


@dataclass(frozen=True, eq=False)
class Transform:
    """One ``*TRANSFORM`` card: ``kind`` ``"R"`` or ``"C"``, its two points, its node set."""

    nset: str
    kind: str
    a: tuple[float, float, float]
    b: tuple[float, float, float]
    location: Location


#: Distance from a ``TYPE=C`` axis below which a node is on it (absolute, model units): ccx 2.20
#: takes a node 9.2e-16 (metalforming's punch apex) or 1e-12 away as on the axis and one 1e-9 away
#: as off it (measured, docs/method.md §33.6).
ON_AXIS = 1e-10

#: A unit axis component at most this large counts as zero in :func:`axis_normal` (as in ccx).
_AXIS_COMPONENT = 1e-10


def axis_normal(axis: np.ndarray) -> np.ndarray:
    """ccx 2.20's local 1 at a node on a cylindrical axis ``axis`` (unit 3-vector).

    With ``i`` the first global direction (x, y, z) in which the axis has a component, local 1
    is the unit vector normal to the axis in the plane of global directions ``i`` and ``i + 1``
    (cyclically), with a positive component along ``i + 1``: y for an axis along x, z along y,
    x along z; ``(-2, 1, 0)/sqrt(5)`` for an axis along ``(1, 2, 3)`` (measured against ccx
    2.20 for these and other axes, docs/method.md §33.6).
    """
    axis = np.asarray(axis, dtype=float)
    i = int(np.flatnonzero(np.abs(axis) > _AXIS_COMPONENT)[0])
    j = (i + 1) % 3
    normal = np.zeros(3)
    normal[j] = 1.0
    normal[i] = -axis[j] / axis[i]
    return normal / np.linalg.norm(normal)


def local_directions(transform: Transform, coords: np.ndarray) -> np.ndarray:
    """The local unit directions ``(n, 3, 3)`` (rows: local 1, 2, 3) at nodes ``coords (n, 3)``.

    A node on a cylinder's axis (closer to it than :data:`ON_AXIS`, as in ccx 2.20) has no
    radial direction: local 3 is the axis there too and local 1 is :func:`axis_normal`
    (docs/method.md §30.4, §33.3, §33.6).

    Raises:
        ValueError: degenerate points.
    """
    a, b = np.asarray(transform.a, float), np.asarray(transform.b, float)
    n = coords.shape[0]
    if transform.kind == "R":
        e1 = a / np.linalg.norm(a) if np.linalg.norm(a) > 0 else None
        if e1 is None:
            raise ValueError("*TRANSFORM, TYPE=R: point a is the origin")
        e2 = b - np.dot(b, e1) * e1
        if np.linalg.norm(e2) == 0:
            raise ValueError("*TRANSFORM, TYPE=R: point b lies on the local x axis")
        e2 /= np.linalg.norm(e2)
        return np.tile(np.stack([e1, e2, np.cross(e1, e2)]), (n, 1, 1))
    axis = b - a
    if np.linalg.norm(axis) == 0:
        raise ValueError("*TRANSFORM, TYPE=C: the two points coincide")
    axis /= np.linalg.norm(axis)
    offset = coords - a
    radial = offset - np.outer(offset @ axis, axis)
    length = np.linalg.norm(radial, axis=1)
    on_axis = length < ON_AXIS
    radial[~on_axis] /= length[~on_axis, None]
    # on the axis: local 3 stays the axis (ccx 2.20 moves metalforming's axis nodes along it,
    # measured, docs/method.md §30.4), local 1 ccx's normal to it (measured, §33.6)
    radial[on_axis] = axis_normal(axis)
    tangential = np.cross(axis, radial)
    out = np.stack([radial, tangential, np.broadcast_to(axis, radial.shape)], axis=1)
    return out


class TransformCards(ReaderState):
    """The ``*TRANSFORM`` handler and the rewriting of the ``*BOUNDARY`` lines it affects."""

    def _k_TRANSFORM(self, card: Card) -> None:
        self._check_params(card, allowed={"NSET", "TYPE"}, required={"NSET"})
        nset = card.params["NSET"] or ""
        if nset not in self.nsets:
            raise DeckError(f"node set {nset} is not defined (before this line)", card.location)
        kind = card.params.get("TYPE") or "R"
        if kind not in ("R", "C"):
            raise DeckError(f"*TRANSFORM, TYPE={kind}: R or C expected", card.location)
        self._need_data(card)
        fields, _, loc = card.lines[0]
        if len(fields) != 6 or len(card.lines) != 1:
            raise DeckError("*TRANSFORM needs one data line of six coordinates", loc)
        values = [self._float(f, "coordinate", loc) for f in fields]
        self.transforms.append(
            Transform(nset, kind, tuple(values[:3]), tuple(values[3:]), card.location)
        )

    def _apply_transforms(self, node_ids: np.ndarray, node_coords: np.ndarray) -> None:
        """Rewrite the ``*BOUNDARY`` lines of transformed nodes in global dofs (module doc)."""
        if not self.transforms:
            return
        directions = np.tile(np.eye(3), (node_ids.size, 1, 1))
        transformed = np.zeros(node_ids.size, dtype=bool)
        for transform in self.transforms:  # a later card wins for a node in several
            rows = np.searchsorted(node_ids, np.unique(self.nsets[transform.nset]))
            try:
                directions[rows] = local_directions(transform, node_coords[rows])
            except ValueError as error:
                raise DeckError(str(error), transform.location) from None
            transformed[rows] = True
        held = node_ids[transformed]
        others = [("*EQUATION", e.nodes, e.location) for e in self.equations]
        others += [("*INITIAL CONDITIONS", c.nodes, c.location) for c in self.initial_velocities]
        for keyword, nodes, location in others:  # ccx reads their dofs in the local directions
            if np.isin(nodes, held).any():
                node = int(np.asarray(nodes)[np.isin(nodes, held)][0])
                raise DeckError(
                    f"{keyword} on node {node}, which has a *TRANSFORM, is not supported yet "
                    "(ccx writes a transformed node's SPCs, MPCs and forces in its local system)",
                    location,
                )
        self.boundaries = self._global_boundaries(
            self.boundaries, node_ids, directions, transformed, model=True
        )
        for k, step in enumerate(self.steps):
            for load in step.cloads:  # ccx applies them in the local directions too
                rows = np.searchsorted(node_ids, load.nodes)
                if transformed[rows].any():
                    node = int(load.nodes[transformed[rows]][0])
                    raise DeckError(
                        f"*CLOAD on node {node}, which has a *TRANSFORM, is not supported yet "
                        "(ccx applies it in the node's local directions)",
                        load.location,
                    )
            lines = self._global_boundaries(
                list(step.boundaries), node_ids, directions, transformed, model=False
            )
            self.steps[k] = dataclasses.replace(step, boundaries=tuple(lines))

    def _global_boundaries(
        self,
        lines: list[Boundary],
        node_ids: np.ndarray,
        directions: np.ndarray,
        transformed: np.ndarray,
        *,
        model: bool,
    ) -> list[Boundary]:
        """The lines in global dofs; model-definition zero rows of a node become equations."""
        out: list[Boundary] = []
        zero_rows: dict[int, list[tuple[np.ndarray, Boundary]]] = {}
        for line in lines:
            rows = np.searchsorted(node_ids, line.nodes)
            local = transformed[rows]
            if not local.any():
                out.append(line)
                continue
            if not local.all():  # the untransformed nodes keep the line
                kept = frozen_array(line.nodes[~local], np.int64)
                out.append(dataclasses.replace(line, nodes=kept))
            for row in rows[local]:
                node = int(node_ids[row])
                for dof in range(line.first_dof, line.last_dof + 1):
                    e = directions[row, dof - 1]
                    axis = int(np.argmax(np.abs(e)))
                    if abs(e[axis]) >= 1 - ALIGNED:
                        out.append(dataclasses.replace(
                            line, nodes=frozen_array([node], np.int64), first_dof=axis + 1,
                            last_dof=axis + 1, value=line.value * float(np.sign(e[axis])),
                        ))  # fmt: skip
                    elif line.value == 0.0 and model and line.amplitude is None:
                        zero_rows.setdefault(node, []).append((e, line))
                    else:
                        raise DeckError(
                            f"*BOUNDARY of node {node} along its local direction {dof} "
                            f"({', '.join(f'{c:.6g}' for c in e)}, *TRANSFORM) is not supported "
                            "yet: only zero values in the model definition, or directions along "
                            "a global axis",
                            line.location,
                        )
        for node, terms in zero_rows.items():
            out += self._node_equations(node, terms)
        return out

    def _node_equations(
        self, node: int, terms: list[tuple[np.ndarray, Boundary]]
    ) -> list[Boundary]:
        """The zero local directions of one node as equations with distinct dependent dofs."""
        matrix = np.array([e for e, _ in terms])
        location = terms[0][1].location
        reduced = []
        work = matrix.copy()
        used: list[int] = []
        for _ in range(min(3, work.shape[0])):  # Gauss-Jordan with full pivoting per row
            free = [c for c in range(3) if c not in used]
            sub = np.abs(work[:, free])
            if sub.size == 0 or sub.max() <= 1e-12:
                break
            r, c = np.unravel_index(np.argmax(sub), sub.shape)
            column = free[c]
            pivot = work[r] / work[r, column]
            others = np.delete(work, r, axis=0)
            others = others - np.outer(others[:, column], pivot)
            for row in reduced:
                row -= row[column] * pivot
            reduced.append(pivot)
            used.append(column)
            work = others
        lines: list[Boundary] = []
        for row, dependent in zip(reduced, used):
            row[np.abs(row) <= 1e-15] = 0.0
            nonzero = [dependent] + [c for c in range(3) if c != dependent and row[c] != 0.0]
            if len(nonzero) == 1:
                line = terms[0][1]
                lines.append(dataclasses.replace(
                    line, nodes=frozen_array([node], np.int64), first_dof=dependent + 1,
                    last_dof=dependent + 1, value=0.0,
                ))  # fmt: skip
                continue
            self.equations.append(Equation(
                frozen_array([node] * len(nonzero), np.int64),
                frozen_array([c + 1 for c in nonzero], np.int64),
                frozen_array([row[c] for c in nonzero], np.float64), location,
            ))  # fmt: skip
        return lines
