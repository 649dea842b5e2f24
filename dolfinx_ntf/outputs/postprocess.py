"""What users compute after a solve: reaction forces, and the contact force and area of a pair.

All functions are collective (every process of the mesh's communicator must call them) and return
global values, the same on every process. They read the problem at its current displacement
(docs/method.md §8).
"""

from __future__ import annotations

import numbers
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.pair import ContactPair
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.fem.surfaces import FacetSurface
from dolfinx_ntf.outputs.results import ContactResults, contact_results

__all__ = ["contact_area", "contact_force", "reaction"]


def reaction(
    problem: ContactProblem,
    facets: FacetSurface | np.ndarray | None = None,
    *,
    dofs: np.ndarray | compat.DirichletBC | typing.Sequence[compat.DirichletBC] | None = None,
) -> np.ndarray:
    """Reaction force: the residual ``R(u) = f_int - f_ext`` summed over a set of dofs.

    ``R`` is the assembled residual of the problem without its Dirichlet conditions: the user's
    UFL residual ``F`` (internal forces minus the loads written in ``F``), plus the contact spring
    forces, minus the problem's nodal loads. At dofs whose displacement is prescribed it is the
    force that the support exerts on the body (CalculiX's RF); at a converged free dof it is zero.
    So the reaction of a clamped base under a body pressed down is an upward force, and the sum of
    all reactions balances the loads.

    Args:
        problem: The contact problem, at the displacement to evaluate (e.g. after a solve).
        facets: The facets whose nodes to sum over, all components: a
            :class:`~dolfinx_ntf.FacetSurface`, or local facet indices (e.g.
            ``facet_tags.find(TAG)``).
        dofs: Or the dofs to sum over: a Dirichlet condition (or a list of them), whose
            constrained dofs are taken, or local dof indices of the displacement space as
            ``bc.dof_indices()[0]`` or ``locate_dofs_topological((V.sub(i), Vi), ...)[0]`` give
            them (unrolled: ``d node + component``, ``d`` = 3, or 2 on a 2D mesh).

    Returns:
        ``(d,)`` the summed force per component (zero for components without selected dofs): on a
        2D mesh per the thickness the residual form is written for (per unit thickness in plane
        strain).
    """
    owner = "reaction"
    validation.check_type(problem, ContactProblem, f"{owner}: problem")
    if (facets is None) == (dofs is None):
        raise TypeError(f"{owner}: give either facets or dofs (exactly one of them)")
    V = problem.u.function_space
    num_owned = V.dofmap.index_map.size_local
    bs = V.dofmap.index_map_bs
    rows = _facet_dofs(V, facets, owner) if facets is not None else _selected_dofs(V, dofs, owner)
    rows = rows[rows < bs * num_owned]  # owned dofs only: each counted once over the processes
    residual = _unconstrained_residual(problem)
    local = np.zeros(bs)
    np.add.at(local, rows % bs, residual[rows])
    return V.mesh.comm.allreduce(local, op=MPI.SUM)


def _facet_dofs(V: dolfinx.fem.FunctionSpace, facets: object, owner: str) -> np.ndarray:
    """Unrolled local dofs of the nodes of ``facets``."""
    mesh = V.mesh
    tdim = mesh.topology.dim
    if isinstance(facets, FacetSurface):
        if facets.tags.dim != tdim - 1:
            raise ValueError(f"{owner}: facets must be facet tags (dimension {tdim - 1})")
        facets = facets.tags.indices[np.isin(facets.tags.values, facets.value_list())]
    indices = _indices(facets, f"{owner}: facets")
    num_facets = mesh.topology.index_map(tdim - 1).size_local
    num_facets += mesh.topology.index_map(tdim - 1).num_ghosts
    _check_range(indices, num_facets, f"{owner}: facets", "facet")
    mesh.topology.create_connectivity(tdim - 1, tdim)
    nodes = dolfinx.fem.locate_dofs_topological(V, tdim - 1, indices.astype(np.int32))
    bs = V.dofmap.index_map_bs
    return (bs * np.asarray(nodes, dtype=np.int64)[:, None] + np.arange(bs)).ravel()


def _selected_dofs(V: dolfinx.fem.FunctionSpace, dofs: object, owner: str) -> np.ndarray:
    """Unrolled local dofs from Dirichlet conditions or an index array."""
    if isinstance(dofs, compat.DirichletBC):
        dofs = [dofs]
    if isinstance(dofs, (list, tuple)) and dofs and isinstance(dofs[0], compat.DirichletBC):
        bcs = validation.check_sequence(dofs, compat.DirichletBC, f"{owner}: dofs")
        return np.unique(np.concatenate([np.asarray(bc.dof_indices()[0]) for bc in bcs]))
    indices = _indices(dofs, f"{owner}: dofs")
    num_dofs = V.dofmap.index_map_bs * (
        V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    )
    _check_range(indices, num_dofs, f"{owner}: dofs", "dof")
    return np.unique(indices)


def _indices(values: object, what: str) -> np.ndarray:
    """A 1-D int64 array of indices, or a TypeError naming ``what``."""
    array = np.asarray(values)
    if array.ndim != 1 or (array.size and not np.issubdtype(array.dtype, np.integer)):
        raise TypeError(
            f"{what} must be a 1-D array of integer indices, got {validation.describe(values)}"
        )
    return array.astype(np.int64)


def _check_range(indices: np.ndarray, size: int, what: str, kind: str) -> None:
    """Indices outside ``0..size-1``: a ValueError naming the first."""
    bad = np.flatnonzero((indices < 0) | (indices >= size))
    if bad.size:
        i = int(bad[0])
        raise ValueError(
            f"{what}: {kind} index {int(indices[i])} (entry {i}) is outside 0..{size - 1}"
        )


def _unconstrained_residual(problem: ContactProblem) -> np.ndarray:
    """Local values (owned and ghost dofs) of R(u) without Dirichlet conditions."""
    b = compat.create_vector(problem.L)
    try:
        with b.localForm() as local:
            local.set(0.0)
        dolfinx.fem.petsc.assemble_vector(b, problem.L)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        problem.assembler.add_to_vector(b, problem.evaluate(tangent=False), dirichlet_rows=True)
        x = compat.petsc_vector(problem.u)  # element terms with their Dirichlet rows: no bcs
        blocks = [term.evaluate(x, (), tangent=False) for term in problem.element_terms]
        if blocks:
            problem.assembler.add_global_to_vector(b, blocks)
        if problem.nodal_loads is not None:
            b.axpy(-1.0, compat.petsc_vector(problem.nodal_loads))
        return b.array.copy()
    finally:
        b.destroy()


def _pair_results(
    problem: ContactProblem, pair: int | str | ContactPair | None, owner: str
) -> list[ContactResults]:
    """The results of the selected pair (all pairs for None)."""
    validation.check_type(problem, ContactProblem, f"{owner}: problem")
    results = contact_results(problem)
    if pair is None:
        return results
    # a master of several face types gives a state (and results) per type, one pair number
    pair_numbers = problem.pairing.pair_numbers
    names = [
        r.pair for n, r in enumerate(results) if n == 0 or pair_numbers[n] != pair_numbers[n - 1]
    ]
    if isinstance(pair, ContactPair):
        index = next(
            (n for n, s in zip(pair_numbers, problem.pairing.states) if s.pair is pair), None
        )
    elif isinstance(pair, str):
        index = next((n for n, r in zip(pair_numbers, results) if r.pair == pair), None)
    elif isinstance(pair, numbers.Integral) and not isinstance(pair, bool):
        index = int(pair) if 0 <= pair < len(names) else None
    else:
        raise TypeError(
            f"{owner}: pair must be an index, a name, a ContactPair or None, got "
            f"{validation.describe(pair)}"
        )
    if index is None:
        raise ValueError(f"{owner}: no pair {pair!r} in the problem (pairs: {names})")
    return [res for n, res in zip(pair_numbers, results, strict=True) if n == index]


def contact_force(
    problem: ContactProblem, pair: int | str | ContactPair | None = None
) -> np.ndarray:
    """Total contact force on the slave side of a pair (or of all pairs). Collective.

    The sum of the spring forces on the slave nodes (``ContactResults.force``): the force the
    master body exerts on the slave body through the contact.

    Args:
        problem: The contact problem.
        pair: Index (from 0), name or :class:`~dolfinx_ntf.ContactPair` of the pair; ``None``
            sums all pairs.

    Returns:
        ``(d,)`` force vector (``d`` = 3, or 2 on a 2D mesh, where it is the force over the
        pair's ``thickness``).
    """
    results = _pair_results(problem, pair, "contact_force")
    dim = problem.u.function_space.dofmap.index_map_bs
    local = sum((r.force.sum(axis=0) for r in results), np.zeros(dim))
    return problem.u.function_space.mesh.comm.allreduce(local, op=MPI.SUM)


def contact_area(problem: ContactProblem, pair: int | str | ContactPair | None = None) -> float:
    """Contact area of a pair (or of all pairs): the spring areas of its closed springs. Collective.

    A spring is closed where its clearance is negative (``contact_status`` 1); its area ``A_p`` is
    the slave area the node stands for (docs/method.md §2.2), in the current configuration; on a
    2D mesh the contact length times the pair's ``thickness``.

    Args:
        problem: The contact problem.
        pair: Index (from 0), name or :class:`~dolfinx_ntf.ContactPair` of the pair; ``None``
            sums all pairs.
    """
    results = _pair_results(problem, pair, "contact_area")
    local = sum(float(r.area[r.clearance < 0].sum()) for r in results)
    return float(problem.u.function_space.mesh.comm.allreduce(local, op=MPI.SUM))
