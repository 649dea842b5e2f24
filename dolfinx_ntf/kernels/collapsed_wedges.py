"""Wedges (6-node prisms) as hexahedra with one collapsed edge (docs/method.md §30, §32).

The wedge ``1..6`` (triangle ``1-2-3`` below ``4-5-6``, ccx's C3D6 and gmsh's 6-node prism
order) becomes the hexahedron ``1, 2, 3, 3, 4, 5, 6, 6`` (ccx's C3D8 order): its face ``3-3-6-6``
collapses into the edge ``3-6``. dolfinx then treats it as any hexahedron. The deck runner
(``calculix/deck/wedges.py``) and the gmsh reader (``meshes/gmsh_io.py``) share this module.

dolfinx corrupts its memory (0.5.2, 0.9 and 0.11, measured) when a collapsed edge is shared by
more than two cells, or by two cells that also share a face; two cells that share only the
collapsed edge build. Each wedge is therefore first turned (its corners renumbered cyclically,
``rotation`` 0..2, which keeps the element and its orientation): wedges stacked on shared
triangles repeat the same corner there (so the triangle is one facet of both), and the collapsed
edges are kept apart (``shared=False``) or shared by at most two wedges with no common face
(``shared=True``, the gmsh reader).
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "HEXAHEDRON_FACETS",
    "WEDGE_AS_HEXAHEDRON",
    "WedgeRotationError",
    "collapse_wedges",
    "collapsed_jacobians",
    "rotated_wedges",
    "unmatched_neighbours",
    "wedge_rotations",
]

#: Hexahedron node ``k`` (ccx's C3D8 order) of a collapsed wedge is the wedge's node
#: ``WEDGE_AS_HEXAHEDRON[k]`` (0-based).
WEDGE_AS_HEXAHEDRON = np.array([0, 1, 2, 2, 3, 4, 5, 5], dtype=np.int64)

# 2x2x2 Gauss points of the unit cube, and the trilinear shape function gradients there.
_G = 0.5 / np.sqrt(3.0)
_POINTS = np.array([[0.5 + a, 0.5 + b, 0.5 + c] for c in (-_G, _G) for b in (-_G, _G)
                    for a in (-_G, _G)])  # fmt: skip
_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float
)


class WedgeRotationError(ValueError):
    """No rotation of the wedges keeps their collapsed edges as dolfinx needs them.

    Attributes:
        index: Row of a wedge of the stack that could not be placed.
    """

    def __init__(self, message: str, index: int) -> None:
        super().__init__(message)
        self.index = index


def _hex_gradients() -> np.ndarray:
    """``(q, 8, 3)`` reference gradients of the trilinear shape functions (ccx corner order)."""
    sign = 2.0 * _CORNERS - 1.0  # +1 at the far side of each axis
    value = 1.0 - _CORNERS[None] + sign[None] * _POINTS[:, None, :]  # (q, 8, 3) 1D factors
    grads = np.empty((_POINTS.shape[0], 8, 3))
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        grads[:, :, axis] = sign[None, :, axis] * value[:, :, others[0]] * value[:, :, others[1]]
    return grads


_GRADIENTS = _hex_gradients()


def collapsed_jacobians(coords: np.ndarray) -> np.ndarray:
    """``(e, 8)`` Jacobian determinants of collapsed wedges at the 2x2x2 Gauss points.

    ``coords`` ``(e, 8, 3)``: the collapsed hexahedra's nodes in ccx's C3D8 order (positive for
    a wedge whose triangle ``1-2-3`` turns counter-clockwise seen from ``4-5-6``).
    """
    jac = np.einsum("eki,qkj->eqij", coords, _GRADIENTS)
    return np.linalg.det(jac)


def rotated_wedges(rows: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """The wedges ``rows`` ``(e, 6)`` with their corners renumbered cyclically by ``rotation``."""
    rows = np.asarray(rows)
    turn = (np.arange(3)[None, :] + np.asarray(rotation)[:, None]) % 3  # (e, 3)
    return np.concatenate(
        [np.take_along_axis(rows[:, :3], turn, 1), np.take_along_axis(rows[:, 3:], turn, 1)],
        axis=1,
    )


def collapse_wedges(rows: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """``(e, 8)`` collapsed hexahedra (ccx's C3D8 order) of the wedges turned by ``rotation``."""
    return rotated_wedges(rows, rotation)[:, WEDGE_AS_HEXAHEDRON]


#: The six facets of a hexahedron in dolfinx's tensor vertex order.
HEXAHEDRON_FACETS = np.array(
    [[0, 1, 2, 3], [0, 1, 4, 5], [0, 2, 4, 6], [1, 3, 5, 7], [2, 3, 6, 7], [4, 5, 6, 7]], np.int64
)


# the four vertex triples of a sorted facet row (of a collapsed triangle, one is distinct)
_TRIPLES = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]], dtype=np.int64)


def unmatched_neighbours(cells: np.ndarray) -> np.ndarray:
    """``(k, 2)`` pairs ``i < j`` of hexahedra that share a face dolfinx does not match.

    dolfinx pairs two cells through a facet whose sorted vertex lists are equal. A collapsed
    wedge's triangle is the list ``a, b, c, c``: it matches only a triangle of a wedge repeating
    the same corner, never the quadrilateral ``a, b, c, d`` of a hexahedron lying on it nor a
    triangle repeating another corner. Returned: the pairs of cells with unmatched facets that
    have three distinct vertices in common, and no matched facet between them (docs/method.md
    §37). None for a conforming mesh of hexahedra. At most two cells on a face (a manifold
    mesh, as dolfinx's facet matching assumes too).

    Args:
        cells: ``(n, 8)`` hexahedra in dolfinx's tensor vertex order (collapsed ones repeat a
            vertex), vertex numbers.
    """
    cells = np.asarray(cells, dtype=np.int64)
    n = cells.shape[0]
    # every facet's sorted vertex list (dolfinx's key) and its cell, sorted by key
    facets = np.sort(cells[:, HEXAHEDRON_FACETS].reshape(-1, 4), axis=1)
    owner = np.repeat(np.arange(n, dtype=np.int64), HEXAHEDRON_FACETS.shape[0])
    order = np.lexsort(facets.T[::-1])
    facets, owner = facets[order], owner[order]
    same = np.all(facets[1:] == facets[:-1], axis=1)
    matched_keys = np.minimum(owner[1:], owner[:-1])[same] * n
    matched_keys += np.maximum(owner[1:], owner[:-1])[same]
    alone = ~(np.r_[same, False] | np.r_[False, same])
    # the unmatched facets' triples of distinct vertices (a quadrilateral has four, a collapsed
    # triangle one, a collapsed face none), then cells meeting on a triple
    triples = facets[alone][:, _TRIPLES].reshape(-1, 3)
    holder = np.repeat(owner[alone], _TRIPLES.shape[0])
    real = (triples[:, 0] < triples[:, 1]) & (triples[:, 1] < triples[:, 2])
    triples, holder = triples[real], holder[real]
    order = np.lexsort(np.column_stack([triples, holder]).T[::-1])
    triples, holder = triples[order], holder[order]
    meet = np.flatnonzero(np.all(triples[1:] == triples[:-1], axis=1) & (holder[1:] != holder[:-1]))
    keys = np.unique(np.minimum(holder[meet], holder[meet + 1]) * n
                     + np.maximum(holder[meet], holder[meet + 1]))  # fmt: skip
    keys = keys[~np.isin(keys, matched_keys)]
    return np.column_stack([keys // n, keys % n]) if n else np.zeros((0, 2), dtype=np.int64)


def _rotated(row: list[int], rotation: int) -> list[int]:
    """The wedge ``row`` (6 nodes) with its corners renumbered cyclically by ``rotation``.

    Plain lists: called once per wedge and choice, where small numpy arrays cost more than the work.
    """
    turn = [(i + rotation) % 3 for i in range(3)]
    return [row[i] for i in turn] + [row[3 + i] for i in turn]


def wedge_rotations(rows: np.ndarray, *, shared: bool = False) -> np.ndarray:
    """Rotation 0..2 of each wedge (rows ``(e, 6)`` in ccx order) for its collapsed hexahedron.

    Wedges stacked on shared triangles are turned together so that they repeat the same corner
    there. ``shared=False``: no two wedges collapse onto the same edge (depth-first over the
    stacks; the deck runner's rule). ``shared=True``: an edge may be the collapsed edge of two
    wedges that share no face (a seeded local search over the stacks; needed where a layer has more
    stacks than vertical edges, as every extruded triangulation). Set-up work, once per mesh.

    Raises:
        WedgeRotationError: no rotation satisfies the rule (``index``: a wedge that is in the way).
    """
    rows = np.asarray(rows, dtype=np.int64)
    lists = rows.tolist()
    triangles: dict[frozenset, list[int]] = {}
    for k, row in enumerate(lists):
        for tri in (row[:3], row[3:]):
            triangles.setdefault(frozenset(tri), []).append(k)
    rotation = np.full(rows.shape[0], -1, dtype=np.int64)
    stacks: list[list[dict[int, int]]] = []  # per stack, its choices (wedge -> rotation)
    for start in range(rows.shape[0]):
        if rotation[start] >= 0:
            continue
        choices = []
        for first in range(3):
            chosen = _stack(start, first, lists, triangles)
            edges = [_edge(lists[k], r) for k, r in chosen.items()]
            if len(set(edges)) == len(edges):
                choices.append(chosen)
        rotation[list(chosen)] = 0  # visited
        stacks.append(choices)
    if shared:
        picks = _pick_shared(stacks, rows)
    else:
        picks = _pick([[{_edge(lists[k], r) for k, r in c.items()} for c in ch] for ch in stacks])
    if isinstance(picks, int) or picks is None:
        stack = 0 if picks is None else picks
        index = int(next(iter(stacks[stack][0]))) if stacks and stacks[stack] else 0
        rule = "at most two wedges with no common face" if shared else "apart"
        raise WedgeRotationError(
            "no numbering of the wedges' corners keeps their collapsed edges " + rule, index
        )
    for choices, pick in zip(stacks, picks):
        for k, r in choices[pick].items():
            rotation[k] = r
    return rotation


def _edge(row: list[int], rotation: int) -> frozenset:
    """The collapsed edge (nodes 3 and 6 after turning) of the wedge ``row``."""
    corner = (2 + rotation) % 3
    return frozenset((row[corner], row[3 + corner]))


def _pick(edge_sets: list[list[set[frozenset]]], limit: int = 100000) -> list[int] | None:
    """One choice per stack whose collapsed edges are all distinct (depth-first), or None.

    ``edge_sets[s][c]``: the collapsed edges of choice ``c`` of stack ``s``.
    """
    picks: list[int] = []
    used: list[set[frozenset]] = []
    steps = 0
    next_choice = 0
    while len(picks) < len(edge_sets):
        steps += 1
        if steps > limit:
            return None
        taken = set().union(*used) if used else set()
        choices = edge_sets[len(picks)]
        for c in range(next_choice, len(choices)):
            if not taken & choices[c]:
                picks.append(c)
                used.append(choices[c])
                next_choice = 0
                break
        else:
            if not picks:
                return None
            next_choice = picks.pop() + 1
            used.pop()
    return picks


def _pick_shared(
    stacks: list, rows: np.ndarray, sweeps: int = 200, seed: int = 0
) -> list[int] | int:
    """One choice per stack under the shared rule, or a stack still in conflict.

    A greedy start along a breadth-first front (:func:`_front_order`): each stack takes a choice
    without conflict, moving the stacks in its way (up to three rounds, undone if they fail:
    short augmenting paths to the spare edges next to the front), else its least conflicting
    choice; ties go to the edges already used most (best fit). Then a min-conflicts local search
    (seeded, so the same mesh gives the same rotations) on the few conflicts left: a stack in
    conflict moves to its least conflicting choice (a random one with probability 0.2) until none
    is left or ``sweeps`` times the number of stacks moves are done. Every step is local (O(1)):
    the stacks in conflict are a list with an index (no sort per move), edges are integers.
    """
    for s, choices in enumerate(stacks):
        if not choices:
            return s
    rng = np.random.default_rng(seed)
    nodes = [set(row) for row in rows.tolist()]
    options, num_edges = _edge_options(stacks, rows)
    users: list[list[tuple[int, int]]] = [[] for _ in range(num_edges)]
    pick = [-1] * len(stacks)

    def cost(s: int, c: int) -> int:
        """Conflicts of choice ``c`` of stack ``s`` with the other stacks' current choices."""
        total = 0
        for k, edge in options[s][c]:
            others = [w for t, w in users[edge] if t != s]
            if others:
                total += len(others) if len(others) >= 2 else 0
                total += sum(len(nodes[k] & nodes[w]) >= 3 for w in others)  # a common face
        return total

    def move(s: int, c: int) -> None:
        """Stack ``s`` takes choice ``c`` (-1: none)."""
        if pick[s] >= 0:
            for _, edge in options[s][pick[s]]:
                users[edge] = [(t, w) for t, w in users[edge] if t != s]
        pick[s] = c
        if c >= 0:
            for k, edge in options[s][c]:
                users[edge].append((s, k))

    def settle(s: int, depth: int, log: list, path: set) -> bool:
        """Give ``s`` a conflict-free choice, moving the stacks in its way (``depth`` deep)."""
        for c in sorted(range(len(options[s])), key=lambda c: fill(s, c)):
            log.append((s, pick[s]))
            move(s, c)
            if cost(s, c) == 0:
                return True
            if depth:
                mark = len(log)
                ways = {t for _, edge in options[s][c] for t, _ in users[edge]} - path - {s}
                if all(settle(t, depth - 1, log, path | {s}) for t in sorted(ways)):
                    if cost(s, c) == 0:
                        return True
                while len(log) > mark:
                    move(*log.pop())
        return False

    def place(s: int) -> None:
        """Greedy step: ``s`` without conflict if two rounds of moves allow, else least bad."""
        log: list[tuple[int, int]] = []
        if settle(s, 3, log, set()) and all(cost(t, pick[t]) == 0 for t, _ in log):
            return
        while log:
            move(*log.pop())
        move(s, min(range(len(options[s])), key=lambda c: fill(s, c)))

    def fill(s: int, c: int) -> tuple[int, int]:
        """Greedy key: fewest conflicts, then the edges already used most (best fit)."""
        return cost(s, c), -sum(len(users[edge]) for _, edge in options[s][c])

    for s in _front_order(options, num_edges):  # greedy start, along a front
        place(s)
    bad = _IndexedSet(s for s in range(len(stacks)) if cost(s, pick[s]))
    for _ in range(sweeps * len(stacks)):
        if not bad:
            return pick
        s = bad.item(int(rng.integers(len(bad))))
        if rng.random() < 0.2:
            c = int(rng.integers(len(options[s])))
        else:
            costs = [cost(s, c) for c in range(len(options[s]))]
            best = [c for c, value in enumerate(costs) if value == min(costs)]
            c = best[int(rng.integers(len(best)))]
        touched = {t for _, edge in options[s][pick[s]] for t, _ in users[edge]}
        move(s, c)
        touched |= {t for _, edge in options[s][c] for t, _ in users[edge]}
        for t in touched:
            if cost(t, pick[t]):
                bad.add(t)
            else:
                bad.discard(t)
    return min(bad.items) if bad else pick  # no stacks at all: no moves, nothing in conflict


def _front_order(options: list, num_edges: int) -> list[int]:
    """The stacks in breadth-first order over shared candidate edges, from a central stack.

    A front grown from the middle of each connected part ends on its boundary, where the spare
    edges are (a layer has about twice as many stacks as vertical lines, fewer at the boundary):
    the greedy start leaves its conflicts there, next to the room that resolves them. The centre:
    the stack nearest both ends of a long path (two sweeps from an end found by a third).
    """
    near: list[list[int]] = [[] for _ in range(num_edges)]
    for s, choices in enumerate(options):
        for choice in choices:
            for _, edge in choice:
                near[edge].append(s)
    seen = [False] * len(options)
    order: list[int] = []
    for root in range(len(options)):
        if seen[root]:
            continue
        part, _ = _sweep(root, options, near)
        _, first = _sweep(part[-1], options, near)
        far = max(first, key=first.__getitem__)
        _, second = _sweep(far, options, near)
        centre = min(part, key=lambda s: (max(first[s], second[s]), s))
        part, _ = _sweep(centre, options, near)
        for s in part:
            seen[s] = True
        order.extend(part)
    return order


def _sweep(root: int, options: list, near: list) -> tuple[list[int], dict[int, int]]:
    """Breadth-first order and distances of the stacks reached from ``root``."""
    distance = {root: 0}
    queue = [root]
    head = 0
    while head < len(queue):
        s = queue[head]
        head += 1
        for choice in options[s]:
            for _, edge in choice:
                for t in near[edge]:
                    if t not in distance:
                        distance[t] = distance[s] + 1
                        queue.append(t)
    return queue, distance


class _IndexedSet:
    """A set of integers with O(1) insertion, removal and access by position (random picks)."""

    def __init__(self, values) -> None:
        self.items: list[int] = []
        self._position: dict[int, int] = {}
        for value in values:
            self.add(value)

    def __len__(self) -> int:
        return len(self.items)

    def item(self, position: int) -> int:
        return self.items[position]

    def add(self, value: int) -> None:
        if value not in self._position:
            self._position[value] = len(self.items)
            self.items.append(value)

    def discard(self, value: int) -> None:
        position = self._position.pop(value, None)
        if position is None:
            return
        last = self.items.pop()
        if last != value:
            self.items[position] = last
            self._position[last] = position


def _edge_options(stacks: list, rows: np.ndarray) -> tuple[list, int]:
    """``options[s][c]``: (wedge, collapsed edge number) of choice ``c`` of stack ``s``; edges.

    The edges of all choices at once (numpy): the sorted node pairs numbered by ``np.unique``.
    """
    wedge = np.fromiter((k for ch in stacks for c in ch for k in c), np.int64)
    turn = np.fromiter((r for ch in stacks for c in ch for r in c.values()), np.int64)
    ends = np.sort(rotated_wedges(rows[wedge], turn)[:, [2, 5]], axis=1)
    _, number = np.unique(ends, axis=0, return_inverse=True)
    pairs = list(zip(wedge.tolist(), number.ravel().tolist()))
    options, start = [], 0
    for ch in stacks:
        mine = []
        for c in ch:
            mine.append(pairs[start : start + len(c)])
            start += len(c)
        options.append(mine)
    return options, int(number.max(initial=-1)) + 1


def _stack(start: int, first: int, rows: list[list[int]], triangles: dict) -> dict[int, int]:
    """Rotations of the wedges stacked on ``start``'s triangles when ``start`` takes ``first``.

    A neighbour repeats the corner the wedge repeats on their shared triangle.
    """
    chosen = {start: first}
    todo = [start]
    while todo:
        k = todo.pop()
        row = _rotated(rows[k], chosen[k])
        for tri, repeated in ((row[:3], row[2]), (row[3:], row[5])):
            for other in triangles[frozenset(tri)]:
                if other in chosen:
                    continue
                position = rows[other].index(repeated) % 3
                chosen[other] = (position - 2) % 3  # its corner 3 after turning
                todo.append(other)
    return chosen
