"""Linear constraints of all processes in one global numbering (docs/method.md §14.6).

Each process gives the constraints it knows in its local numbering (owned or ghost nodes of the
displacement space). The elimination needs them all, on every process, in the same order: they
are mapped to PETSc's global unrolled dofs and allgathered, in process order, and a constraint
given by several processes (the same terms, coefficients, value and name, e.g. built per cell on
both sides of a partition cut) counts once. Every process then chooses the same dependent dofs.

A constraint among nodes that no single process holds is written with node *ids* instead (the
mesh's input node indices, or any numbering the caller gives): :func:`global_constraints` finds
the owner of each id and returns :class:`GlobalLinearConstraint` objects in the global numbering,
which any process may pass (docs/method.md §14.9).

A :class:`LinearConstraintBlock` (C3D20's face and cell centres, §13.5) stays a block: its rows
are gathered as arrays and a row given by several processes (a face centre of a face between
cells of two processes) counts once, the first in process order (docs/method.md §14.10).
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.fem.constraints import (
    ConstraintElimination,
    LinearConstraint,
    LinearConstraintBlock,
)

__all__ = [
    "GlobalLinearConstraint",
    "GlobalLinearConstraintBlock",
    "distributed_elimination",
    "gather_constraints",
    "global_constraint_block",
    "global_constraints",
    "input_node_ids",
]


class GlobalLinearConstraint(LinearConstraint):
    """A :class:`LinearConstraint` whose ``nodes`` are global block dofs of the space.

    PETSc's numbering of the displacement space (``index_map.local_to_global``; on one process the
    local block dofs), so any process may give it, whichever processes hold its nodes. Made by
    :func:`global_constraints` (docs/method.md §14.9). ``components``, ``coefficients``, ``value``
    and ``name`` are those of :class:`LinearConstraint`.
    """


class GlobalLinearConstraintBlock(LinearConstraintBlock):
    """A :class:`~dolfinx_ntf.LinearConstraintBlock` whose ``nodes`` are global block dofs.

    The block form of :class:`GlobalLinearConstraint` (surface ties, cyclic symmetry: §19), made
    by ``global_constraint_block``; any process may give rows of it.
    """


def input_node_ids(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Input index of the mesh node at each local block dof of ``V`` (owned, then ghosts).

    The node's position in the points given to ``dolfinx.mesh.create_mesh`` (a mesh file's node
    order), the same on any number of processes. ``V`` must have the geometry's cell layout
    (Lagrange of the mesh's degree), else ``ValueError``.
    """
    mesh = V.mesh
    cells = mesh.topology.index_map(mesh.topology.dim)
    num_cells = cells.size_local + cells.num_ghosts
    geometry = compat.geometry_dofs(mesh)[:num_cells]
    space = compat.cell_dofs(V)[:num_cells]
    if geometry.shape != space.shape:
        raise ValueError(
            "input_node_ids: the space's cell layout differs from the geometry's (use Lagrange "
            "of the mesh's degree, or pass node_ids)"
        )
    index_map = V.dofmap.index_map
    ids = np.full(index_map.size_local + index_map.num_ghosts, -1, dtype=np.int64)
    inputs = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    ids[space.ravel()] = inputs[geometry.ravel()]
    return ids


def global_constraints(
    V: dolfinx.fem.FunctionSpace,
    constraints: typing.Sequence[LinearConstraint],
    node_ids: np.ndarray | None = None,
) -> list[GlobalLinearConstraint]:
    """Constraints written with node ids, in ``V``'s global numbering. Collective.

    The terms' nodes may be held by any processes, none of which needs to hold them all: the
    owner of each id gives its global block dof (docs/method.md §14.9).

    Args:
        V: The displacement space (block size 3, or 2 on a 2D mesh).
        constraints: This process's constraints, whose ``nodes`` are node ids. Each process may
            give any constraints; one given by several processes counts once in ``ContactProblem``.
        node_ids: Id of each local block dof of ``V`` (owned, then ghosts; -1 for none), the same
            on every process holding the node. Default :func:`input_node_ids`.

    Returns:
        The constraints as :class:`GlobalLinearConstraint`, in the given order.

    Raises:
        ValueError: on every process, naming the constraint and the id, for an id that no process
            holds or that several nodes carry.
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    num_local = index_map.size_local + index_map.num_ghosts
    error = None
    try:
        for c in constraints:
            validation.check_type(c, LinearConstraint, "global_constraints: constraints")
        ids = input_node_ids(V) if node_ids is None else np.asarray(node_ids, dtype=np.int64)
        if ids.shape != (num_local,):
            raise ValueError(
                f"global_constraints: node_ids needs one id per local block dof ({num_local}), "
                f"got shape {ids.shape} on process {comm.rank}"
            )
    except (TypeError, ValueError) as exc:
        error = exc
    validation.raise_collectively(comm, error)
    parts = [c.nodes for c in constraints]
    wanted = np.unique(np.concatenate(parts)) if parts else np.zeros(0, np.int64)
    wanted, found, count = _owners_of_ids(V, ids, wanted)
    result, error = [], None
    for c in constraints:
        where = np.searchsorted(wanted, c.nodes)
        bad = count[where] != 1
        if np.any(bad):
            node, many = int(c.nodes[bad][0]), bool(count[where][bad][0])
            error = ValueError(
                f"{c.label}: node {node}: "
                + ("several nodes carry this id" if many else "no node of the mesh has this id")
            )
            break
        result.append(
            GlobalLinearConstraint(found[where], c.components, c.coefficients, c.value, c.name)
        )
    validation.raise_collectively(comm, error)
    return result


def _owners_of_ids(
    V: dolfinx.fem.FunctionSpace, ids: np.ndarray, wanted: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Global block dof and number of carriers of every id wanted by any process. Collective.

    Returns ``(wanted, found, count)``: the sorted union of all processes' ``wanted``, the global
    block dof of each (-1 for none) and how many owned nodes carry it (1 when well defined).
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    wanted = np.unique(np.asarray(wanted, dtype=np.int64))
    if comm.size > 1:
        wanted = np.unique(np.concatenate(comm.allgather(wanted)))
    # each owner answers for the ids of its owned nodes (an id on several nodes is counted)
    order = np.argsort(ids[: index_map.size_local], kind="stable")
    owned = ids[order]
    first = np.searchsorted(owned, wanted, side="left")
    count = (np.searchsorted(owned, wanted, side="right") - first).astype(np.int64)
    found = np.full(wanted.size, -1, dtype=np.int64)
    found[count > 0] = int(index_map.local_range[0]) + order[first[count > 0]]
    if comm.size > 1:
        comm.Allreduce(MPI.IN_PLACE, found, op=MPI.MAX)
        comm.Allreduce(MPI.IN_PLACE, count, op=MPI.SUM)
    return wanted, found, count


def global_constraint_block(
    V: dolfinx.fem.FunctionSpace,
    block: LinearConstraintBlock,
    node_ids: np.ndarray | None = None,
) -> GlobalLinearConstraintBlock:
    """A block written with node ids, in ``V``'s global numbering. Collective.

    The array form of :func:`global_constraints` (docs/method.md §14.9): each process may give
    any rows (an empty block where it has none), on nodes any processes hold.

    Args:
        V: The displacement space (block size 3, or 2 on a 2D mesh).
        block: This process's rows, whose ``nodes`` are node ids.
        node_ids: Id of each local block dof of ``V`` (see :func:`global_constraints`).

    Raises:
        ValueError: on every process, naming the block and the id, for an id that no process
            holds or that several nodes carry.
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    ids = input_node_ids(V) if node_ids is None else np.asarray(node_ids, dtype=np.int64)
    num_local = index_map.size_local + index_map.num_ghosts
    error = None
    if ids.shape != (num_local,):
        error = ValueError(
            f"global_constraint_block: node_ids needs one id per local block dof ({num_local}), "
            f"got shape {ids.shape} on process {comm.rank}"
        )
    validation.raise_collectively(comm, error)
    wanted, found, count = _owners_of_ids(V, ids, block.nodes.ravel())
    where = np.searchsorted(wanted, block.nodes)
    bad = count[where] != 1
    if np.any(bad):
        node, many = int(block.nodes[bad][0]), bool(count[where][bad][0])
        error = ValueError(
            f"{block.name}: node {node}: "
            + ("several nodes carry this id" if many else "no node of the mesh has this id")
        )
    validation.raise_collectively(comm, error)
    return GlobalLinearConstraintBlock(
        found[where],
        block.components,
        block.coefficients,
        block.values,
        name=block.name,
        drop_prescribed=block.drop_prescribed,
    )


def gather_constraints(
    comm: MPI.Comm,
    constraints: typing.Sequence[LinearConstraint | LinearConstraintBlock],
    global_dofs: np.ndarray,
    block_size: int = 3,
) -> list[LinearConstraint | LinearConstraintBlock]:
    """Every process's constraints with global dofs, each once, in process order. Collective.

    Blocks are gathered block by block (by position in each process's list, then name): one
    block per name and width, its rows in process order, a repeated row once.

    Args:
        comm: The communicator.
        constraints: This process's constraints (local block dofs, ghosts included, or
            :class:`GlobalLinearConstraint`).
        global_dofs: Global unrolled dof of every local unrolled dof.
        block_size: Components per node (3; 2 on a 2D mesh: constraint blocks only, §23).
    """
    local, error = [], None
    for c in constraints:
        if isinstance(c, GlobalLinearConstraint):  # already global (§14.9)
            local.append(("one", c.dofs, c.coefficients, c.value, c.name))
            continue
        if isinstance(c, GlobalLinearConstraintBlock):  # already global (§19)
            local.append(("block", c.dofs, c.coefficients, c.values, (c.name, c.drop_prescribed)))
            continue
        if c.dofs.size and c.dofs.max() >= global_dofs.size:
            node = int(c.nodes.max())
            error = ValueError(
                f"{getattr(c, 'label', c.name)}: node {node} is not a node of process "
                f"{comm.rank} (local nodes 0..{global_dofs.size // block_size - 1}, ghosts "
                "included)"
            )
            break
        if isinstance(c, LinearConstraintBlock):
            block = (c.name, c.drop_prescribed)
            local.append(("block", global_dofs[c.dofs], c.coefficients, c.values, block))
        else:
            local.append(("one", global_dofs[c.dofs], c.coefficients, c.value, c.name))
    validation.raise_collectively(comm, error)
    seen: set[tuple] = set()
    result: list[LinearConstraint | LinearConstraintBlock] = []
    # ((name, drop_prescribed), width) -> [position in result, parts]
    blocks: dict[tuple[tuple[str, bool], int], list] = {}
    for part in comm.allgather(local):
        for kind, dofs, coefficients, value, name in part:
            if kind == "block":
                key = (name, dofs.shape[1])
                if key not in blocks:
                    blocks[key] = [len(result), []]
                    result.append(None)
                blocks[key][1].append((dofs, coefficients, value))
                continue
            order = np.argsort(dofs, kind="stable")
            key = (dofs[order].tobytes(), coefficients[order].tobytes(), value, name)
            if key in seen:
                continue
            seen.add(key)
            if block_size != 3:
                raise NotImplementedError(f"{name}: single constraints on a 2D space")
            result.append(LinearConstraint(dofs // 3, dofs % 3, coefficients, value, name))
    for ((name, drop), _), (position, parts) in blocks.items():
        result[position] = _merged_block(name, parts, drop, block_size)
    return result


def _merged_block(
    name: str, parts: list, drop_prescribed: bool, block_size: int = 3
) -> LinearConstraintBlock:
    """One block of the rows of ``parts`` ``(dofs, coefficients, values)``, each row once."""
    dofs = np.vstack([d for d, _, _ in parts])
    coefficients = np.vstack([np.broadcast_to(c, d.shape) for d, c, _ in parts])
    values = np.concatenate([v for _, _, v in parts])
    order = np.argsort(dofs, axis=1, kind="stable")  # a row's terms in any order: the same key
    sorted_dofs = np.take_along_axis(dofs, order, axis=1)
    sorted_coefficients = np.take_along_axis(coefficients, order, axis=1)
    keys = np.hstack(
        [sorted_dofs, sorted_coefficients.view(np.int64), values.view(np.int64)[:, None]]
    )
    _, first = np.unique(keys, axis=0, return_index=True)
    rows = np.sort(first)
    return LinearConstraintBlock(
        dofs[rows] // block_size,
        dofs[rows] % block_size,
        coefficients[rows],
        values[rows],
        name=name,
        drop_prescribed=drop_prescribed,
        block_size=block_size,
    )


def distributed_elimination(
    V: dolfinx.fem.FunctionSpace,
    constraints: typing.Sequence[LinearConstraint],
    prescribed: np.ndarray,
) -> ConstraintElimination:
    """The elimination of all processes' constraints on ``V``'s distributed layout. Collective.

    Args:
        V: The displacement space (block size 3, or 2 on a 2D mesh).
        constraints: This process's constraints (local numbering).
        prescribed: This process's local unrolled Dirichlet dofs (ghosts included).
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    num_local = index_map.size_local + index_map.num_ghosts
    nodes = index_map.local_to_global(np.arange(num_local, dtype=np.int32)).astype(np.int64)
    bs = V.dofmap.index_map_bs
    global_dofs = (bs * nodes[:, None] + np.arange(bs)).ravel()
    everything = gather_constraints(comm, constraints, global_dofs, bs)
    terms = np.unique(np.concatenate([c.dofs.ravel() for c in everything]))
    fixed = global_dofs[np.asarray(prescribed, dtype=np.int64)]
    in_terms = np.concatenate(comm.allgather(fixed[np.isin(fixed, terms)]))
    owned = fixed[np.asarray(prescribed) < bs * index_map.size_local]
    return ConstraintElimination(
        bs * index_map.size_global,
        everything,
        np.union1d(in_terms, owned),
        comm,
        first_dof=bs * int(index_map.local_range[0]),
        num_owned=bs * index_map.size_local,
    )
