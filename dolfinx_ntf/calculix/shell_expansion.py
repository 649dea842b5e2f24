"""The expansion of 8-node (4-node) shells into 20-node (8-node) bricks, as ccx 2.20 does it.

See docs/method.md §24. ccx replaces every S8 (S8R) element by a C3D20 (C3D20R) element: each
shell node gets three new nodes on its nodal normal ``n``, at ``-(1/2 + offset) t``,
``-offset t`` and ``(1/2 - offset) t`` from it (bottom, middle, top; ``t`` the thickness,
``offset`` in units of ``t``). The normal is the normed mean of the elements' normals at the node
(S8 shape functions). The brick's corners 1-4 are the bottom nodes of the shell corners, 5-8 the
top ones, its midside nodes 9-12 the bottom nodes of the shell's midside nodes, 13-16 the top
ones, 17-20 the middle nodes of the shell corners (a midside node's middle node is numbered but
not used). An S4 becomes an 8-node brick of its bottom (1-4) and top (5-8) nodes. New node
numbers follow the largest node number, three per shell node (bottom,
middle, top), shell nodes taken element by element in deck order, each node once. Measured
with ccx 2.20's ``.frd`` (``*NODE FILE, OUTPUT=3D``). Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "KNOT_ANGLE",
    "ShellExpansion",
    "expand_shells",
    "s8_node_normals",
]

#: ccx makes a knot (a rigid body, not reproduced) where the element normals at a node differ by
#: more than this angle (degrees) from the lowest-numbered element's (ccx manual, S8).
KNOT_ANGLE = 20.0

# S8 nodes in the shell's local coordinates (xi, eta) in [-1, 1]^2, ccx order.
_S8_LOCAL = np.array(
    [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0]], dtype=np.float64
)


def _s8_gradients(points: np.ndarray) -> np.ndarray:
    """``(p, 8, 2)`` derivatives of the 8 serendipity shape functions at ``points (p, 2)``."""
    xi, eta = points[:, 0:1], points[:, 1:2]
    xi_i, eta_i = _S8_LOCAL[None, :, 0], _S8_LOCAL[None, :, 1]
    corner = (xi_i != 0) & (eta_i != 0)
    d_xi = np.where(
        corner,
        0.25 * xi_i * (1 + eta * eta_i) * (2 * xi * xi_i + eta * eta_i),
        np.where(xi_i == 0, -xi * (1 + eta * eta_i), 0.5 * xi_i * (1 - eta**2)),
    )
    d_eta = np.where(
        corner,
        0.25 * eta_i * (1 + xi * xi_i) * (xi * xi_i + 2 * eta * eta_i),
        np.where(xi_i == 0, 0.5 * eta_i * (1 - xi**2), -eta * (1 + xi * xi_i)),
    )
    return np.stack([d_xi, d_eta], axis=-1)


_GRADIENTS_AT_NODES = _s8_gradients(_S8_LOCAL)
# S4: bilinear, d N_i / d xi = xi_i (1 + eta eta_i) / 4 at the corners (p, 4, 2).
_S4_GRADIENTS_AT_NODES = np.stack(
    [
        0.25 * _S8_LOCAL[None, :4, 0] * (1 + _S8_LOCAL[:4, 1:2] * _S8_LOCAL[None, :4, 1]),
        0.25 * _S8_LOCAL[None, :4, 1] * (1 + _S8_LOCAL[:4, 0:1] * _S8_LOCAL[None, :4, 0]),
    ],
    axis=-1,
)


def s8_node_normals(coords: np.ndarray) -> np.ndarray:
    """``(E, n, 3)`` unit normals of S8 (S4) elements ``coords (E, 8 or 4, 3)`` at their nodes.

    ``d x / d xi`` cross ``d x / d eta``: counter-clockwise nodes seen from the normal's tip.

    Raises:
        ValueError: an element is degenerate at a node (no normal).
    """
    table = _GRADIENTS_AT_NODES if coords.shape[1] == 8 else _S4_GRADIENTS_AT_NODES
    tangents = np.einsum("pnk,enx->epkx", table, coords)
    normals = np.cross(tangents[..., 0, :], tangents[..., 1, :])
    length = np.linalg.norm(normals, axis=-1)
    scale = np.linalg.norm(tangents[..., 0, :], axis=-1) * np.linalg.norm(
        tangents[..., 1, :], axis=-1
    )
    bad = np.argwhere(~(length > 1e-12 * scale))
    if bad.size:
        raise ValueError(
            f"shell element row {int(bad[0, 0])} has no normal at its node {int(bad[0, 1]) + 1}"
        )
    return normals / length[..., None]


@dataclass(frozen=True, eq=False)
class ShellExpansion:
    """The expanded nodes of the shell nodes and how ccx prints a shell node from them.

    Attributes:
        nodes: ``(S,)`` shell node numbers, ascending.
        expanded: ``(S, 3)`` their bottom, middle and top node numbers.
        corner: ``(S,)`` True for S8 corner nodes (their middle node is used); S8 midside nodes
            and S4 nodes have a bottom and a top node only.
        normals: ``(S, 3)`` unit nodal normals.
    """

    nodes: np.ndarray
    expanded: np.ndarray
    corner: np.ndarray
    normals: np.ndarray

    def weights(self) -> np.ndarray:
        """``(S, 3)`` weights of bottom, middle, top in the value ccx prints at a shell node.

        Corner nodes: the mean of the quadratic through the thickness, ``(1, 4, 1) / 6``;
        midside nodes: the mean of bottom and top (measured: ccx 2.20's ``.dat`` against its
        ``.frd`` of the expanded nodes, docs/method.md §24).
        """
        return np.where(self.corner[:, None], [[1 / 6, 4 / 6, 1 / 6]], [[0.5, 0.0, 0.5]])

    def hidden(self) -> np.ndarray:
        """Nodes ccx's ``.frd`` leaves out: the shell nodes and the unused middle nodes."""
        return np.sort(np.concatenate([self.nodes, self.expanded[~self.corner, 1]]))

    def printed(self, node_ids: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``values (N, k)`` at ``node_ids`` (ascending, all deck nodes), shell rows as ccx prints.

        The shell nodes' rows are replaced by ccx's combination of their expanded nodes.
        """
        rows = np.searchsorted(node_ids, self.nodes)
        expanded = values[np.searchsorted(node_ids, self.expanded)]  # (S, 3, k)
        out = np.array(values, copy=True)
        out[rows] = np.einsum("sj,sjk->sk", self.weights(), expanded)
        return out


def expand_shells(
    connectivity: np.ndarray,
    node_ids: np.ndarray,
    node_coords: np.ndarray,
    thickness: np.ndarray,
    offset: np.ndarray,
    element_ids: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, ShellExpansion]:
    """The bricks of S8 elements ``connectivity (E, 8)`` (S4: ``(E, 4)``; node numbers, deck order).

    Args:
        connectivity: ``(E, 8)`` (or ``(E, 4)``) shell node numbers in ccx order, elements in deck
            order.
        node_ids: ``(N,)`` all node numbers of the deck, ascending.
        node_coords: ``(N, 3)`` their coordinates.
        thickness: ``(E,)`` shell thickness of each element.
        offset: ``(E,)`` offset of each element (units of the thickness).
        element_ids: ``(E,)`` element numbers (for error messages).

    Returns:
        ``(new_ids (3S,), new_coords (3S, 3), bricks (E, 20), expansion)``: the new nodes, the
        bricks' node numbers in ccx's C3D20 order (S4: ``(E, 8)``, C3D8 order: bottom, then top)
        and the shell nodes' record.

    Raises:
        ValueError: a node whose elements' normals differ by more than ``KNOT_ANGLE`` or whose
            elements have different thicknesses or offsets (ccx makes a knot there).
    """
    coords = node_coords[np.searchsorted(node_ids, connectivity)]
    element_normals = s8_node_normals(coords)  # (E, 8, 3)
    flat = connectivity.ravel()
    # shell nodes in order of first appearance, element by element (ccx's numbering)
    unique, first = np.unique(flat, return_index=True)
    order = np.argsort(first, kind="stable")
    shell_nodes = unique[order]  # appearance order
    slot = np.empty(unique.size, np.int64)
    slot[order] = np.arange(unique.size)
    node_slot = slot[np.searchsorted(unique, flat)]  # (E*8,) appearance index
    # the reference element of a node is its lowest-numbered element
    width = connectivity.shape[1]  # 8 (S8) or 4 (S4)
    element_of = np.repeat(element_ids, width)
    by_number = np.lexsort((element_of, node_slot))
    _, first_of_slot = np.unique(node_slot[by_number], return_index=True)
    reference = by_number[first_of_slot]  # (S,) flat row of each node's reference element
    normals_flat = element_normals.reshape(-1, 3)
    cosine = np.einsum("ix,ix->i", normals_flat, normals_flat[reference[node_slot]])
    apart = np.flatnonzero(cosine < np.cos(np.radians(KNOT_ANGLE)))
    thick_flat, offset_flat = np.repeat(thickness, width), np.repeat(offset, width)
    ref_rows = reference[node_slot]
    differ = np.flatnonzero(
        (thick_flat != thick_flat[ref_rows]) | (offset_flat != offset_flat[ref_rows])
    )
    if apart.size or differ.size:
        k = int(apart[0] if apart.size else differ[0])
        why = (
            f"the normals of shell elements {int(element_of[k])} and "
            f"{int(element_of[ref_rows[k]])} differ by more than {KNOT_ANGLE:g} degrees"
            if apart.size
            else f"shell elements {int(element_of[k])} and {int(element_of[ref_rows[k]])} have "
            "different thicknesses or offsets"
        )
        raise ValueError(
            f"node {int(flat[k])}: {why}; ccx makes a knot (a rigid body) there, which is not "
            "supported"
        )
    summed = np.zeros((shell_nodes.size, 3))
    np.add.at(summed, node_slot, normals_flat)
    normals = summed / np.linalg.norm(summed, axis=1)[:, None]
    base = node_coords[np.searchsorted(node_ids, shell_nodes)]
    t = thick_flat[reference]
    o = offset_flat[reference]
    levels = np.stack([-(0.5 + o) * t, -o * t, (0.5 - o) * t], axis=1)  # (S, 3)
    new_coords = base[:, None, :] + levels[:, :, None] * normals[:, None, :]
    first_new = int(node_ids.max()) + 1
    expanded = first_new + np.arange(3 * shell_nodes.size).reshape(-1, 3)
    local = expanded[node_slot].reshape(-1, width, 3)  # (E, n, 3): bottom, middle, top
    if width == 4:  # S4 -> 8-node brick: no middle nodes
        bricks = np.concatenate([local[:, :, 0], local[:, :, 2]], axis=1)
    else:
        bricks = np.concatenate(
            [local[:, :4, 0], local[:, :4, 2], local[:, 4:, 0], local[:, 4:, 2], local[:, :4, 1]],
            axis=1,
        )
    corner_nodes = np.unique(connectivity[:, :4]) if width == 8 else np.zeros(0, np.int64)
    is_corner = np.isin(shell_nodes, corner_nodes)
    midside_nodes = np.unique(connectivity[:, 4:])
    both = np.intersect1d(corner_nodes, midside_nodes)
    if both.size:
        raise ValueError(
            f"node {int(both[0])} is a corner of one shell element and a midside node of another"
        )
    ascending = np.argsort(shell_nodes)
    expansion = ShellExpansion(
        nodes=shell_nodes[ascending],
        expanded=expanded[ascending],
        corner=is_corner[ascending],
        normals=normals[ascending],
    )
    return expanded.ravel(), new_coords.reshape(-1, 3), bricks, expansion
