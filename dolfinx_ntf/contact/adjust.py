"""Strain-free moves of slave nodes onto the master (CalculiX's ADJUST), dolfinx glue.

``*CONTACT PAIR, ADJUST=a`` (or ``ADJUST=node set``) moves slave nodes at the first pairing of the
analysis: a node in the set, or with clearance ``g <= a`` (penetrating nodes always, when a
distance is given), gets its *reference* coordinates moved by ``-g n`` so that its clearance
becomes 0 (docs/method.md §11.5). The move changes the mesh geometry, so it creates no strain.
"""

from __future__ import annotations

import typing

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import LinearConstraint, LinearConstraintBlock
from dolfinx_ntf.parallel.halo import NodeHalo

__all__ = ["adjusted_nodes", "follow_geometric_rows", "move_reference_nodes"]


def adjusted_nodes(
    gap: np.ndarray, adjust: float | None, in_set: np.ndarray | None = None
) -> np.ndarray:
    """Which located slave nodes ADJUST moves: ``g <= adjust`` (distance) or membership (set).

    Args:
        gap: ``(k,)`` clearances of the located slave nodes.
        adjust: The distance ``a >= 0``, or None for a node set.
        in_set: ``(k,)`` membership of the located nodes in the node set (set form only).
    """
    if adjust is not None:
        return gap <= adjust
    return np.asarray(in_set, dtype=bool)


def move_reference_nodes(
    V: dolfinx.fem.FunctionSpace,
    reference: np.ndarray,
    dofs: np.ndarray,
    delta: np.ndarray,
    halo: NodeHalo | None = None,
) -> None:
    """Move the reference position of block dofs ``dofs`` by ``delta`` ``(k, 3)``.

    Updates the mesh geometry (the bulk forms see the new coordinates at their next assembly:
    no strain) and ``reference`` (the contact code's copy) in place. With a ``halo`` (several
    processes, collective) ``dofs`` are this process's owned slave nodes, and every process moves
    its copies of all processes' nodes: ghosts and halo nodes alike (docs/method.md §14.6).

    Raises:
        NotImplementedError: A dof without a geometry node (e.g. a P2 midside node on a P1 mesh).
    """
    if halo is not None:
        parts = halo.comm.allgather((halo.global_nodes[dofs], np.asarray(delta).reshape(-1, 3)))
        index = halo.find(np.concatenate([p[0] for p in parts]))
        here = index >= 0
        dofs, delta = index[here], np.vstack([p[1] for p in parts])[here]
        reference[dofs[dofs >= halo.num_local]] += delta[dofs >= halo.num_local]
        delta, dofs = delta[dofs < halo.num_local], dofs[dofs < halo.num_local]
    mesh = V.mesh
    cells = compat.cell_dofs(V)
    geometry = compat.geometry_dofs(mesh)[: cells.shape[0]]
    if geometry.shape[1] != cells.shape[1]:
        raise NotImplementedError(
            "ADJUST needs a displacement space with the degree of the mesh geometry (its nodes "
            "are moved)"
        )
    node_of_dof = np.full(cells.max(initial=-1) + 1, -1, dtype=np.int64)
    node_of_dof[cells.ravel()] = geometry.ravel()
    nodes = node_of_dof[np.asarray(dofs, dtype=np.int64)]
    if np.any(nodes < 0):
        raise NotImplementedError("ADJUST: a slave node to move has no geometry node")
    x = mesh.geometry.x
    x[nodes, :3] += delta
    reference[dofs] += delta


def follow_geometric_rows(
    V: dolfinx.fem.FunctionSpace,
    reference: np.ndarray,
    constraints: typing.Sequence[LinearConstraint | LinearConstraintBlock],
) -> int:
    """Put the dependent nodes of geometric constraint rows where the rows say, after ADJUST.

    The 18-node prism (C3D15) and the 27-node hexahedron (C3D20) carry face and cell centres
    whose positions are the serendipity combinations of the element's nodes; ADJUST moves the
    nodes, and the centres must follow, or the bulk sees other elements than ccx's (C3D15: 1 %
    in CDIS, docs/method.md §38.6). Each ``geometric`` block's rows ``sum_j c_j x[n_j] = 0``
    give ``x[n_0] = -sum_{j>0} c_j x[n_j] / c_0``; the blocks are applied until nothing moves
    (C3D8's midside rows feed C3D20's face rows). Every process moves its own copies (its
    cells' rows, ghosts included), the mesh geometry and ``reference`` alike.

    Args:
        V: The displacement space (the degree of the mesh geometry).
        reference: The contact code's reference coordinates (local nodes first), updated in place.
        constraints: The problem's constraints; only ``geometric`` blocks are used.

    Returns:
        The number of this process's nodes moved.
    """
    blocks = [c for c in constraints if isinstance(c, LinearConstraintBlock) and c.geometric]
    moved = np.zeros(0, dtype=np.int64)
    for _ in range(len(blocks) + 1):
        changed = False
        for c in blocks:
            nodes, comps, coef = c.nodes, c.components, c.coefficients
            target = -np.einsum("kj,kj->k", coef[:, 1:], reference[nodes[:, 1:], comps[:, 1:]])
            target /= coef[:, 0]
            shift = target - reference[nodes[:, 0], comps[:, 0]]
            rows = np.flatnonzero(np.abs(shift) > 1e-14 * (1.0 + np.abs(target)))
            if rows.size == 0:
                continue
            changed = True
            targets, which = np.unique(nodes[rows, 0], return_inverse=True)
            delta = np.zeros((targets.size, 3))  # a node's components are rows of their own
            np.add.at(delta, (which.ravel(), comps[rows, 0]), shift[rows])
            move_reference_nodes(V, reference, targets, delta)
            moved = np.union1d(moved, targets)
        if not changed:
            break
    return int(moved.size)
