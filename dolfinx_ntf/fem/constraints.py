"""Linear multi-point constraints enforced by elimination (docs/method.md §13.1).

A :class:`LinearConstraint` ``sum_k a_k u[n_k, c_k] = value`` (CalculiX ``*EQUATION``) makes one
of its dofs *dependent*: ``u_s = sum_j t_sj u_j + g_s``. Over all constraints this is
``u = T w + g`` with ``w`` the independent dofs. The unknown of the Newton solver stays the full
displacement ``u``; every iteration

    - back-substitutes the dependent dofs from the independent ones (``u_s = T_s u + g_s``),
    - reduces the assembled residual and Jacobian, springs included: ``T'^T r`` and ``T'^T J T'``
      with ``T' = T + E_s`` (``E_s`` the unit diagonal of the dependent dofs), whose dependent
      rows and columns are then replaced by identity rows with a zero right-hand side, and whose
      Dirichlet rows are restored,

so that the solve returns the correction of the independent dofs and a zero correction of the
dependent ones, like the condensed system ``T^T J T`` of dolfinx_mpc but without renumbering. No
penalty is involved: constraints hold to round-off after every update.

:func:`elimination_rows` (pure numpy/scipy) chooses the dependent dofs and resolves chains;
:class:`ConstraintElimination` is the thin PETSc glue.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

__all__ = [
    "ConstraintElimination",
    "LinearConstraint",
    "LinearConstraintBlock",
    "elimination_rows",
    "num_equations",
]


@dataclass(frozen=True, eq=False)
class LinearConstraint:
    """``sum_k coefficients[k] * u[nodes[k], components[k]] = value`` (a ccx ``*EQUATION``).

    The first term whose dof is neither prescribed (Dirichlet) nor already dependent becomes the
    dependent dof, as in CalculiX where the first term is dependent.

    Args:
        nodes: Local block dofs of the displacement space (one per term). In parallel, this
            process's (owned or ghost); the constraints of all processes count, each once
            (docs/method.md §14.6).
        components: Displacement component 0, 1 or 2 of each term.
        coefficients: Coefficient of each term.
        value: Right-hand side (ccx: 0).
        name: Label for messages (e.g. the deck line).
    """

    nodes: typing.Sequence[int] | np.ndarray
    components: typing.Sequence[int] | np.ndarray
    coefficients: typing.Sequence[float] | np.ndarray
    value: float = 0.0
    name: str = ""

    def __post_init__(self) -> None:
        """Check shapes and values (``ValueError`` naming the constraint)."""
        nodes = np.asarray(self.nodes, dtype=np.int64).ravel()
        components = np.asarray(self.components, dtype=np.int64).ravel()
        coefficients = np.asarray(self.coefficients, dtype=float).ravel()
        label = f"LinearConstraint {self.name!r}" if self.name else "LinearConstraint"
        if not (nodes.size == components.size == coefficients.size) or nodes.size == 0:
            raise ValueError(
                f"{label}: nodes, components and coefficients need one entry per term (got "
                f"{nodes.size}, {components.size}, {coefficients.size})"
            )
        if np.any(nodes < 0):
            raise ValueError(f"{label}: node {int(nodes[nodes < 0][0])} is not a mesh node")
        if np.any((components < 0) | (components > 2)):
            raise ValueError(f"{label}: components must be 0, 1 or 2, got {components.tolist()}")
        if not (np.all(np.isfinite(coefficients)) and np.isfinite(self.value)):
            raise ValueError(f"{label}: coefficients and value must be finite")
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "components", components)
        object.__setattr__(self, "coefficients", coefficients)
        object.__setattr__(self, "value", float(self.value))

    @property
    def label(self) -> str:
        """Name for messages."""
        return self.name or "constraint"

    @property
    def dofs(self) -> np.ndarray:
        """Unrolled dofs ``3 node + component`` of the terms."""
        return 3 * self.nodes + self.components


@dataclass(frozen=True, eq=False)
class LinearConstraintBlock:
    """``K`` constraints of ``m`` terms each, as arrays (e.g. C3D20's face centres, §13.5).

    Row ``k`` states ``sum_j coefficients[k, j] * u[nodes[k, j], components[k, j]] = values[k]``
    and behaves like one :class:`LinearConstraint`; a block avoids one Python object per
    constraint on large meshes.

    Args:
        nodes: ``(K, m)`` local block dofs.
        components: ``(K, m)`` components (0, 1 or 2).
        coefficients: ``(K, m)`` or ``(m,)`` (the same for every row) coefficients.
        values: ``(K,)`` right-hand sides; default 0.
        name: Label for messages.
        drop_prescribed: Drop a row whose every term (of non-zero coefficient) is prescribed by
            a Dirichlet condition, instead of refusing it as redundant (surface ties and cyclic
            symmetry on a fixed boundary, §19: the prescribed values are the caller's to keep
            consistent).
        block_size: Components per node of the space (3; 2 on a 2D mesh, e.g. the centres of
            8-node quadrilaterals, §23; 1 on a scalar space, C3D15's temperatures, §39).
        geometric: The rows hold for the node positions too (shape rows: serendipity centres,
            C3D8's straight midside nodes): when ADJUST moves nodes, the dependent nodes'
            positions follow them (docs/method.md §38.6).
    """

    nodes: np.ndarray
    components: np.ndarray
    coefficients: np.ndarray
    values: np.ndarray | None = None
    name: str = "constraint block"
    drop_prescribed: bool = False
    block_size: int = 3
    geometric: bool = False

    def __post_init__(self) -> None:
        """Check shapes and values (``ValueError`` naming the block)."""
        nodes = np.atleast_2d(np.asarray(self.nodes, dtype=np.int64))
        components = np.asarray(self.components, dtype=np.int64)
        coefficients = np.asarray(self.coefficients, dtype=float)
        label = f"LinearConstraintBlock {self.name!r}"
        try:
            components = np.broadcast_to(components, nodes.shape)
            coefficients = np.broadcast_to(coefficients, nodes.shape)
        except ValueError:
            raise ValueError(
                f"{label}: components {components.shape} and coefficients {coefficients.shape} "
                f"do not match nodes {nodes.shape}"
            ) from None
        values = np.zeros(nodes.shape[0]) if self.values is None else np.asarray(self.values, float)
        if nodes.ndim != 2 or nodes.shape[1] == 0 or values.shape != (nodes.shape[0],):
            raise ValueError(f"{label}: nodes must be (K, m) with m > 0 and values (K,)")
        if nodes.size and nodes.min() < 0:
            raise ValueError(f"{label}: node {int(nodes.min())} is not a mesh node")
        if np.any((components < 0) | (components >= self.block_size)):
            allowed = {1: "0", 2: "0 or 1"}.get(self.block_size, "0, 1 or 2")
            raise ValueError(f"{label}: components must be {allowed}")
        if not (np.all(np.isfinite(coefficients)) and np.all(np.isfinite(values))):
            raise ValueError(f"{label}: coefficients and values must be finite")
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "components", components)
        object.__setattr__(self, "coefficients", coefficients)
        object.__setattr__(self, "values", values)

    def __len__(self) -> int:
        """Number of constraints (rows)."""
        return int(self.nodes.shape[0])

    @property
    def dofs(self) -> np.ndarray:
        """``(K, m)`` unrolled dofs ``block_size node + component``."""
        return self.block_size * self.nodes + self.components


Constraints = typing.Sequence[LinearConstraint | LinearConstraintBlock]


def num_equations(constraints: Constraints) -> int:
    """Number of scalar constraints (a block counts its rows)."""
    return sum(len(c) if isinstance(c, LinearConstraintBlock) else 1 for c in constraints)


def _values(constraints: Constraints) -> np.ndarray:
    """Right-hand sides of all scalar constraints in order."""
    parts = [
        c.values if isinstance(c, LinearConstraintBlock) else np.array([c.value])
        for c in constraints
    ]
    return np.concatenate(parts) if parts else np.zeros(0)


def _terms(constraints: Constraints):
    """All terms at once: ``(sizes, dofs, coefficients, label)`` of the scalar constraints.

    ``label(k)`` names scalar constraint ``k``, ``first_dof(k)`` its first term's dof, and
    ``droppable`` marks the rows of blocks with ``drop_prescribed``.
    """
    sizes, dofs, coefficients, owners, droppable = [], [], [], [], []
    for index, c in enumerate(constraints):
        if isinstance(c, LinearConstraintBlock):
            droppable.append(np.full(len(c), c.drop_prescribed))
            sizes.append(np.full(len(c), c.nodes.shape[1]))
            dofs.append(c.dofs.ravel())
            coefficients.append(c.coefficients.ravel())
            owners.append(np.full(len(c), index))
        else:
            droppable.append(np.zeros(1, dtype=bool))
            sizes.append(np.array([c.nodes.size]))
            dofs.append(c.dofs)
            coefficients.append(c.coefficients)
            owners.append(np.array([index]))
    sizes_a = np.concatenate(sizes)
    dofs_a = np.concatenate(dofs)
    starts = np.concatenate([[0], np.cumsum(sizes_a)[:-1]])
    owner_of = np.concatenate(owners)

    def label(k: int) -> str:
        c = constraints[int(owner_of[k])]
        if isinstance(c, LinearConstraintBlock):
            return f"{c.name} (row {k - int(np.flatnonzero(owner_of == owner_of[k])[0])})"
        return c.label

    return (
        sizes_a,
        dofs_a,
        np.concatenate(coefficients),
        label,
        lambda k: int(dofs_a[starts[k]]),
        np.concatenate(droppable),
    )


def elimination_rows(
    num_dofs: int,
    constraints: Constraints,
    prescribed: np.ndarray | None = None,
) -> tuple[np.ndarray, scipy.sparse.csr_matrix, np.ndarray]:
    """Dependent dofs ``s`` and their rows: ``u[s] = M @ u + g`` with no dependent column in M.

    See :func:`_elimination` (``g`` from the constraints' values).
    """
    s, M, G = _elimination(num_dofs, constraints, prescribed)
    return s, M, G @ _values(constraints)


def _elimination(
    num_dofs: int,
    constraints: Constraints,
    prescribed: np.ndarray | None = None,
) -> tuple[np.ndarray, scipy.sparse.csr_matrix, scipy.sparse.csr_matrix]:
    """Dependent dofs ``s`` and their rows: ``u[s] = M @ u + g`` with no dependent column in M.

    Args:
        num_dofs: Number of unrolled dofs.
        constraints: The constraints (a block counts as its rows).
        prescribed: Unrolled dofs with a Dirichlet condition (never made dependent).

    Returns:
        ``(s, M, G)``: dependent dofs in constraint order, ``(len(s), num_dofs)`` CSR rows and the
        ``(len(s), num_equations(constraints))`` map from the constraints' values to the
        offsets ``g``.

    Raises:
        ValueError: a constraint whose every dof is prescribed or dependent already (redundant or
            contradictory with the Dirichlet conditions), or circular constraints.
    """
    fixed = np.zeros(num_dofs, dtype=bool)
    if prescribed is not None and len(prescribed):
        fixed[np.asarray(prescribed, dtype=np.int64)] = True
    if not constraints:
        empty = scipy.sparse.csr_matrix((0, num_dofs))
        return np.zeros(0, np.int64), empty, scipy.sparse.csr_matrix((0, 0))
    # all terms at once: constraint index, dof, coefficient; repeated dofs of a constraint summed
    sizes, dofs, coefficients, label, first_dof, droppable = _terms(constraints)
    num_rows = sizes.size
    owner = np.repeat(np.arange(num_rows), sizes)
    if dofs.size and dofs.max() >= num_dofs:
        bad = int(owner[np.argmax(dofs >= num_dofs)])
        raise ValueError(f"{label(bad)}: dof {int(dofs.max())} is outside the space")
    kept = np.arange(num_rows)
    if np.any(droppable):  # rows of drop_prescribed blocks on prescribed dofs only: dropped
        largest = np.zeros(num_rows)
        np.maximum.at(largest, owner, np.abs(coefficients))
        free = np.zeros(num_rows, dtype=bool)
        significant = np.abs(coefficients) > 1e-14 * largest[owner]
        np.logical_or.at(free, owner, ~fixed[dofs] & significant)
        kept = np.flatnonzero(free | ~droppable)
        terms = np.isin(owner, kept)
        sizes, dofs, coefficients = sizes[kept], dofs[terms], coefficients[terms]
        label, first_dof = _renumbered(label, kept), _renumbered(first_dof, kept)
    count = sizes.size
    owner = np.repeat(np.arange(count), sizes)
    if count == 0:
        empty = scipy.sparse.csr_matrix((0, num_dofs))
        return np.zeros(0, np.int64), empty, scipy.sparse.csr_matrix((0, num_rows))
    keys, first, inverse = np.unique(
        owner * num_dofs + dofs, return_index=True, return_inverse=True
    )
    order = np.argsort(first, kind="stable")  # terms in written order, constraints ascending
    merged = np.bincount(inverse.ravel(), weights=coefficients)[order]
    term_owner, term_dof = (keys // num_dofs)[order], (keys % num_dofs)[order]
    largest = np.zeros(count)
    np.maximum.at(largest, term_owner, np.abs(merged))
    candidate = (np.abs(merged) > 1e-14 * largest[term_owner]) & ~fixed[term_dof]
    # the dependent dof: the first candidate term (sequentially when two constraints pick one dof)
    chosen = np.full(count, -1, dtype=np.int64)
    where = np.flatnonzero(candidate)
    owners, start = np.unique(term_owner[where], return_index=True)
    chosen[owners] = where[start]
    picked = term_dof[chosen[chosen >= 0]]
    if chosen.min() < 0 or np.unique(picked).size != picked.size:
        chosen = _choose_sequentially(term_owner, term_dof, candidate, count)
    missing = np.flatnonzero(chosen < 0)
    if missing.size:
        node, comp = divmod(first_dof(int(missing[0])), 3)
        raise ValueError(
            f"{label(int(missing[0]))}: every dof of the constraint is prescribed by a Dirichlet "
            "condition or already dependent in another constraint (first term: node "
            f"{node}, component {comp}): the constraint is redundant or contradicts them"
        )
    s = term_dof[chosen]
    a = merged[chosen]
    others = np.ones(term_dof.size, dtype=bool)
    others[chosen] = False
    M = scipy.sparse.csr_matrix(
        (-merged[others] / a[term_owner[others]], (term_owner[others], term_dof[others])),
        shape=(s.size, num_dofs),
    )
    # one dependent dof per kept constraint, in order
    G = scipy.sparse.csr_matrix((1.0 / a, (np.arange(count), kept)), shape=(count, num_rows))
    # chains: a dependent dof on the right-hand side of another constraint is substituted, round
    # by round (as many rounds as the longest chain); a cycle is refused first
    chained = M[:, s]
    chained.eliminate_zeros()
    if chained.nnz:
        count, label = scipy.sparse.csgraph.connected_components(chained, connection="strong")
        sizes = np.bincount(label, minlength=count)
        if np.any(sizes > 1):
            cycle = s[sizes[label] > 1]
            raise ValueError(
                "circular constraints: dependent dofs depend on each other (dofs "
                f"{cycle[:5].tolist()}{' ...' if cycle.size > 5 else ''})"
            )
    independent = scipy.sparse.diags((~np.isin(np.arange(num_dofs), s)).astype(float))
    while chained.nnz:
        M = (M @ independent + chained @ M).tocsr()
        G = (G + chained @ G).tocsr()
        chained = M[:, s]
        chained.eliminate_zeros()
    M.sum_duplicates()
    M.eliminate_zeros()
    return s, M, G


class ConstraintElimination:
    """The PETSc operators of ``u = T w + g`` on a vector space (see the module doc).

    In parallel every process passes the same constraints in the global numbering (PETSc's
    unrolled dofs) and builds the rows of ``T`` and ``T'`` it owns (docs/method.md §14.6).

    Args:
        num_dofs: Unrolled dofs of the space (over all processes).
        constraints: The constraints (global dofs; the same on every process).
        prescribed: Unrolled Dirichlet dofs (kept as identity rows, never dependent): in parallel
            those in constraints on any process and those this process owns.
        comm: The mesh communicator.
        first_dof: First dof this process owns.
        num_owned: Dofs this process owns (default all).
    """

    def __init__(
        self,
        num_dofs: int,
        constraints: Constraints,
        prescribed: np.ndarray,
        comm,
        *,
        first_dof: int = 0,
        num_owned: int | None = None,
    ) -> None:
        n = num_dofs if num_owned is None else int(num_owned)
        self._comm = comm
        self.prescribed = np.unique(np.asarray(prescribed, dtype=np.int64))
        self.slaves, rows, self._values_to_offsets = _elimination(
            num_dofs, constraints, self.prescribed
        )
        self.offsets = self._values_to_offsets @ _values(constraints)
        owned = (self.slaves >= first_dof) & (self.slaves < first_dof + n)
        self._owned = np.flatnonzero(owned)  # positions in ``slaves`` of the owned ones
        self._local_slaves = self.slaves[owned] - first_dof  # their local rows
        identity = np.ones(n)
        identity[self._local_slaves] = 0.0
        embed = scipy.sparse.csr_matrix(
            (np.ones(self._owned.size), (self._local_slaves, np.arange(self._owned.size))),
            shape=(n, self._owned.size),
        )
        local = np.arange(n)
        diagonal = scipy.sparse.csr_matrix(
            (identity, (local, first_dof + local)), shape=(n, num_dofs)
        )
        T = (diagonal + embed @ rows[self._owned]).tocsr()
        dependent = scipy.sparse.csr_matrix(
            (1.0 - identity, (local, first_dof + local)), shape=(n, num_dofs)
        )
        self._T = _petsc(T, comm)  # u = T u + g: back-substitution
        self._Tp = _petsc((T + dependent).tocsr(), comm)  # T'
        self._work = self._T.createVecLeft()
        in_range = (self.prescribed >= first_dof) & (self.prescribed < first_dof + n)
        self._eliminated = np.union1d(self.slaves[owned], self.prescribed[in_range]).astype(
            PETSc.IntType
        )
        self._reduced: PETSc.Mat | None = None
        self._reduced_key: tuple | None = None

    @property
    def num_constraints(self) -> int:
        """Number of eliminated (dependent) dofs."""
        return int(self.slaves.size)

    def set_values(self, values: np.ndarray) -> None:
        """New right-hand sides of the constraints (in their order), e.g. prescribed by time."""
        self.offsets = self._values_to_offsets @ np.asarray(values, dtype=float)

    def back_substitute(self, x: PETSc.Vec) -> None:
        """Dependent dofs of ``x`` from the independent ones: ``x = T x + g``."""
        self._T.mult(x, self._work)
        rows = self._local_slaves
        x.array[rows] = self._work.array[rows] + self.offsets[self._owned]

    def reduce_vector(self, b: PETSc.Vec, dirichlet: typing.Callable[[PETSc.Vec], None]) -> None:
        """``b <- T'^T b`` with zero dependent rows; ``dirichlet(b)`` restores Dirichlet rows."""
        self._Tp.multTranspose(b, self._work)
        self._work.copy(b)
        b.array[self._local_slaves] = 0.0
        dirichlet(b)

    def reduce_matrix(self, A: PETSc.Mat, key: tuple) -> PETSc.Mat:
        """``T'^T A T'`` with identity rows and columns at dependent and Dirichlet dofs.

        ``key`` identifies ``A``'s sparsity pattern: the reduced matrix is reused while it is
        unchanged, else made anew.
        """
        reuse = self._reduced is not None and key == self._reduced_key
        if self._comm.size > 1:  # one process's new pattern makes all start afresh
            reuse = self._comm.allreduce(reuse, op=MPI.LAND)
        if reuse:
            A.PtAP(self._Tp, result=self._reduced)
        else:
            if self._reduced is not None:
                self._reduced.destroy()
            self._reduced = A.PtAP(self._Tp)
            self._reduced_key = key
        self._reduced.zeroRowsColumns(self._eliminated, diag=1.0)
        return self._reduced

    def project(self, A: PETSc.Mat, *, diagonal: float) -> PETSc.Mat:
        """A new ``T'^T A T'`` with ``diagonal`` at dependent and Dirichlet dofs (rows, columns).

        For example a mass matrix with zero there (a modal analysis, docs/method.md §16).
        """
        reduced = A.PtAP(self._Tp)
        reduced.zeroRowsColumns(self._eliminated, diag=diagonal)
        return reduced

    def expand(self, x: PETSc.Vec) -> None:
        """Dependent dofs of ``x`` from the independent ones without the offsets: ``x = T x``."""
        self._T.mult(x, self._work)
        rows = self._local_slaves
        x.array[rows] = self._work.array[rows]

    def release(self) -> None:
        """Free the reduced matrix (made again when needed)."""
        if self._reduced is not None:
            self._reduced.destroy()
        self._reduced, self._reduced_key = None, None

    def destroy(self) -> None:
        """Free the PETSc objects."""
        for obj in (self._T, self._Tp, self._work, self._reduced):
            if obj is not None:
                obj.destroy()
        self._reduced = None


def _renumbered(function: typing.Callable[[int], typing.Any], rows: np.ndarray):
    """``function`` of the original row number, called with the number among ``rows``."""
    return lambda k: function(int(rows[k]))


def _choose_sequentially(
    owner: np.ndarray, dof: np.ndarray, candidate: np.ndarray, count: int
) -> np.ndarray:
    """Term index of each constraint's dependent dof: its first candidate not taken before."""
    chosen = np.full(count, -1, dtype=np.int64)
    taken: set[int] = set()
    for term in np.flatnonzero(candidate).tolist():
        k, d = int(owner[term]), int(dof[term])
        if chosen[k] < 0 and d not in taken:
            chosen[k] = term
            taken.add(d)
    return chosen


def _petsc(matrix: scipy.sparse.csr_matrix, comm) -> PETSc.Mat:
    """This process's rows (all columns, global) as a square PETSc matrix of ``comm``."""
    matrix = matrix.tocsr()
    matrix.sort_indices()
    n, size = matrix.shape
    return PETSc.Mat().createAIJ(
        ((n, size), (n, size)),
        csr=(
            matrix.indptr.astype(PETSc.IntType),
            matrix.indices.astype(PETSc.IntType),
            matrix.data.astype(PETSc.ScalarType),
        ),
        comm=comm,
    )
