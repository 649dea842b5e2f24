"""Linear constraints of all processes in one global numbering (docs/method.md §14.6).

Each process gives the constraints it knows in its local numbering (owned or ghost nodes of the
displacement space). The elimination needs them all, on every process, in the same order: they
are mapped to PETSc's global unrolled dofs and allgathered, in process order, and a constraint
given by several processes (the same terms, coefficients and value, e.g. built per cell on both
sides of a partition cut) counts once. Every process then chooses the same dependent dofs.
A :class:`LinearConstraintBlock` (C3D20's face and cell centres, §13.5) stays a block: its rows
are gathered as arrays and a row given by several processes (a face centre of a face between
cells of two processes) counts once, the first in process order (docs/method.md §14.10).
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.constraints import (
    ConstraintElimination,
    LinearConstraint,
    LinearConstraintBlock,
)

__all__ = ["distributed_elimination", "gather_constraints"]


def gather_constraints(
    comm: MPI.Comm,
    constraints: typing.Sequence[LinearConstraint | LinearConstraintBlock],
    global_dofs: np.ndarray,
) -> list[LinearConstraint | LinearConstraintBlock]:
    """Every process's constraints with global dofs, each once, in process order. Collective.

    Blocks are gathered block by block (by position in each process's list, then name): one
    block per name and width, its rows in process order, a repeated row once.

    Args:
        comm: The communicator.
        constraints: This process's constraints (local block dofs, ghosts included).
        global_dofs: Global unrolled dof of every local unrolled dof.
    """
    local, error = [], None
    for c in constraints:
        if c.dofs.size and c.dofs.max() >= global_dofs.size:
            node = int(c.nodes.max())
            error = ValueError(
                f"{getattr(c, 'label', c.name)}: node {node} is not a node of process "
                f"{comm.rank} (local nodes 0..{global_dofs.size // 3 - 1}, ghosts included)"
            )
            break
        if isinstance(c, LinearConstraintBlock):
            local.append(("block", global_dofs[c.dofs], c.coefficients, c.values, c.name))
        else:
            local.append(("one", global_dofs[c.dofs], c.coefficients, c.value, c.name))
    validation.raise_collectively(comm, error)
    seen: set[tuple] = set()
    result: list[LinearConstraint | LinearConstraintBlock] = []
    blocks: dict[tuple[str, int], list] = {}  # (name, width) -> [position in result, parts]
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
            key = (dofs[order].tobytes(), coefficients[order].tobytes(), value)
            if key in seen:
                continue
            seen.add(key)
            result.append(LinearConstraint(dofs // 3, dofs % 3, coefficients, value, name))
    for (name, _), (position, parts) in blocks.items():
        result[position] = _merged_block(name, parts)
    return result


def _merged_block(name: str, parts: list) -> LinearConstraintBlock:
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
        dofs[rows] // 3, dofs[rows] % 3, coefficients[rows], values[rows], name=name
    )


def distributed_elimination(
    V: dolfinx.fem.FunctionSpace,
    constraints: typing.Sequence[LinearConstraint],
    prescribed: np.ndarray,
) -> ConstraintElimination:
    """The elimination of all processes' constraints on ``V``'s distributed layout. Collective.

    Args:
        V: The displacement space (block size 3).
        constraints: This process's constraints (local numbering).
        prescribed: This process's local unrolled Dirichlet dofs (ghosts included).
    """
    comm = V.mesh.comm
    index_map = V.dofmap.index_map
    num_local = index_map.size_local + index_map.num_ghosts
    nodes = index_map.local_to_global(np.arange(num_local, dtype=np.int32)).astype(np.int64)
    global_dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
    everything = gather_constraints(comm, constraints, global_dofs)
    terms = np.unique(np.concatenate([c.dofs.ravel() for c in everything]))
    fixed = global_dofs[np.asarray(prescribed, dtype=np.int64)]
    in_terms = np.concatenate(comm.allgather(fixed[np.isin(fixed, terms)]))
    owned = fixed[np.asarray(prescribed) < 3 * index_map.size_local]
    return ConstraintElimination(
        3 * index_map.size_global,
        everything,
        np.union1d(in_terms, owned),
        comm,
        first_dof=3 * int(index_map.local_range[0]),
        num_owned=3 * index_map.size_local,
    )
