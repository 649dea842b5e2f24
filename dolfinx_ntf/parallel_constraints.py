"""Linear constraints of all processes in one global numbering (docs/method.md §14.6).

Each process gives the constraints it knows in its local numbering (owned or ghost nodes of the
displacement space). The elimination needs them all, on every process, in the same order: they
are mapped to PETSc's global unrolled dofs and allgathered, in process order, and a constraint
given by several processes (the same terms, coefficients and value, e.g. built per cell on both
sides of a partition cut) counts once. Every process then chooses the same dependent dofs.
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.constraints import ConstraintElimination, LinearConstraint

__all__ = ["distributed_elimination", "gather_constraints"]


def gather_constraints(
    comm: MPI.Comm,
    constraints: typing.Sequence[LinearConstraint],
    global_dofs: np.ndarray,
) -> list[LinearConstraint]:
    """Every process's constraints with global dofs, each once, in process order. Collective.

    Args:
        comm: The communicator.
        constraints: This process's constraints (local block dofs, ghosts included).
        global_dofs: Global unrolled dof of every local unrolled dof.
    """
    local, error = [], None
    for c in constraints:
        if c.dofs.max() >= global_dofs.size:
            node = int(c.nodes.max())
            error = ValueError(
                f"{c.label}: node {node} is not a node of process {comm.rank} (local nodes "
                f"0..{global_dofs.size // 3 - 1}, ghosts included)"
            )
            break
        local.append((global_dofs[c.dofs], c.coefficients, c.value, c.name))
    validation.raise_collectively(comm, error)
    seen: set[tuple] = set()
    result = []
    for part in comm.allgather(local):
        for dofs, coefficients, value, name in part:
            order = np.argsort(dofs, kind="stable")
            key = (dofs[order].tobytes(), coefficients[order].tobytes(), value)
            if key in seen:
                continue
            seen.add(key)
            result.append(LinearConstraint(dofs // 3, dofs % 3, coefficients, value, name))
    return result


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
    terms = np.unique(np.concatenate([c.dofs for c in everything]))
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
