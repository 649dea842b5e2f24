"""Contact pressure recovered as a traction field on the contact boundary (docs/method.md §15.3).

Node-to-face springs report a pressure per node, ``F_N / A_p`` (CalculiX's CSTR): the law's value at
the node's overclosure. On quadratic faces corner nodes carry almost no spring area, so that value
says little about the traction. The recovered pressure is instead the field ``p_h`` of the scalar
Lagrange space of ``u`` on the contact boundary whose work-equivalent nodal forces are the spring
forces::

    ∫_Γ p_h φ_i ds = F_N,i   for every node i of Γ,

solved with the boundary mass matrix, lumped (row sums, P1 only: ``p_i = F_N,i / ∫ φ_i``) or
consistent. For the continuum formulations the right-hand side is ``∫_Γ λ(u) φ_i ds`` with their
pressure expression ``λ`` (an L2 projection onto the trace space). Either way ``∫_Γ p_h ds`` equals
the total normal force exactly (up to the linear solve), and every formulation is measured on the
same kind of field.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat

__all__ = ["BoundaryPressure"]


class BoundaryPressure:
    """Projection of contact pressures onto the boundary trace of ``u``'s scalar space.

    Args:
        V: The (vector) displacement space.
        facets: Local indices of the contact boundary's facets (e.g. ``facet_tags.find(tag)``).
        lumped: Lumped (row-sum) mass; default for P1 (positive, local), consistent for higher
            degrees (whose lumped corner masses vanish).
        quadrature_degree: Degree of the right-hand side integrals of :meth:`from_expression`.
    """

    def __init__(
        self,
        V: dolfinx.fem.FunctionSpace,
        facets: np.ndarray,
        *,
        lumped: bool | None = None,
        quadrature_degree: int = 8,
    ) -> None:
        mesh = V.mesh
        facets = np.unique(np.asarray(facets, dtype=np.int32))
        facet_tags = dolfinx.mesh.meshtags(
            mesh, mesh.topology.dim - 1, facets, np.ones_like(facets)
        )
        tag = 1
        self.degree = compat.space_degree(V)
        self.lumped = self.degree == 1 if lumped is None else bool(lumped)
        if self.lumped and self.degree > 1:
            raise ValueError(
                "BoundaryPressure: lumped recovery needs P1 (the lumped masses of quadratic corner "
                "nodes vanish); use lumped=False"
            )
        Q, dofs = compat.component_space(V, 0)
        self.space = Q
        node_of_q = np.asarray(dofs) // V.dofmap.index_map_bs  # 3, or 2 on a 2D mesh
        self._q_of_node = np.full(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, -1)
        self._q_of_node[node_of_q] = np.arange(node_of_q.size)
        self._node_of_q = node_of_q
        fdim = mesh.topology.dim - 1
        #: A prism mesh (dolfinx 0.11: two facet types, no ``ds``) has no recovery: no facets.
        self._empty = mesh.topology.cell_type == dolfinx.mesh.CellType.prism
        if self._empty:
            if mesh.comm.allreduce(facets.size, op=MPI.SUM):
                raise NotImplementedError(
                    "BoundaryPressure: facets of prism meshes are not supported (method §34)"
                )
            self.dofs = np.zeros(0, dtype=np.int32)
            self.pressure = dolfinx.fem.Function(Q, name="contact_pressure_recovered")
            return
        mesh.topology.create_connectivity(fdim, mesh.topology.dim)
        boundary = dolfinx.fem.locate_dofs_topological(Q, fdim, facets)
        self.dofs = np.asarray(boundary, dtype=np.int32)
        #: The recovered pressure (zero off the contact boundary).
        self.pressure = dolfinx.fem.Function(Q, name="contact_pressure_recovered")
        self._ds = ufl.Measure(
            "ds",
            domain=mesh,
            subdomain_data=facet_tags,
            metadata={"quadrature_degree": quadrature_degree},
        )(tag)
        self._ds_exact = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)(tag)
        q = ufl.TestFunction(Q)
        self._rhs = compat.create_vector(dolfinx.fem.form(q * self._ds_exact))
        weights = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(q * self._ds_exact))
        weights.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        self._weights = weights
        self._ksp = None
        if not self.lumped:
            p = ufl.TrialFunction(Q)
            num_local = Q.dofmap.index_map.size_local + Q.dofmap.index_map.num_ghosts
            off = np.setdiff1d(np.arange(num_local, dtype=np.int32), self.dofs)
            zero = dolfinx.fem.Function(Q)
            bc = dolfinx.fem.dirichletbc(zero, off.astype(np.int32))
            self._bc = [bc]
            # The zero volume term puts every diagonal in the sparsity pattern (off-boundary rows
            # get the Dirichlet diagonal 1; a ds-only pattern lacks them).
            zero_volume = dolfinx.fem.Constant(mesh, PETSc.ScalarType(0.0)) * p * q * ufl.dx
            mass = dolfinx.fem.form(p * q * self._ds_exact + zero_volume)
            M = dolfinx.fem.petsc.assemble_matrix(mass, [bc])
            M.assemble()
            ksp = PETSc.KSP().create(mesh.comm)
            ksp.setOperators(M)
            ksp.setType("preonly")
            ksp.getPC().setType("lu")
            ksp.getPC().setFactorSolverType("mumps")
            self._M, self._ksp = M, ksp

    def _solve(self, rhs: PETSc.Vec) -> dolfinx.fem.Function:
        target = compat.petsc_vector(self.pressure)
        if self.lumped:
            values = np.zeros_like(rhs.array)
            w = self._weights.array
            on = w > 0
            values[on] = rhs.array[on] / w[on]
            target.array[:] = 0.0
            target.array[: values.size] = values
        else:
            dolfinx.fem.petsc.set_bc(rhs, self._bc)
            self._ksp.solve(rhs, target)
        target.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        return self.pressure

    def from_forces(self, nodes: np.ndarray, forces: np.ndarray) -> dolfinx.fem.Function:
        """Recover from normal forces ``forces`` at ``nodes`` (block indices of ``u``'s space).

        Forces at ghost nodes are ignored (their owner has them). Collective.

        Args:
            nodes: ``(N,)`` local block indices of ``u``'s space (e.g. ``ContactResults.node``).
            forces: ``(N,)`` normal force at each node (e.g. the springs').

        Returns:
            ``self.pressure``, updated.

        Raises:
            ValueError: A node outside the displacement space (on every process).
        """
        if self._empty:
            return self.pressure
        rhs = self._rhs
        with rhs.localForm() as local:
            local.set(0.0)
        q = self._q_of_node[np.asarray(nodes, dtype=np.int64)]
        if self.space.mesh.comm.allreduce(bool(np.any(q < 0)), op=MPI.LOR):  # fail on all ranks
            raise ValueError("BoundaryPressure.from_forces: nodes outside the displacement space")
        owned = q < rhs.getLocalSize()
        np.add.at(rhs.array, q[owned], np.asarray(forces, dtype=float)[owned])
        return self._solve(rhs)

    def from_expression(self, pressure: ufl.core.expr.Expr) -> dolfinx.fem.Function:
        """L2-project a UFL pressure expression (e.g. ``K [-g]_+``) onto the trace space.

        Collective.

        Args:
            pressure: Scalar UFL expression of the contact pressure, e.g.
                :func:`~dolfinx_ntf.fem.continuum.penalty_pressure`.

        Returns:
            ``self.pressure``, updated.
        """
        rhs = self._rhs
        with rhs.localForm() as local:
            local.set(0.0)
        q = ufl.TestFunction(self.space)
        dolfinx.fem.petsc.assemble_vector(rhs, dolfinx.fem.form(pressure * q * self._ds))
        rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        return self._solve(rhs)

    def total(self) -> float:
        """``∫_Γ p_h ds``: the total normal force the recovered field carries. Collective."""
        if self._empty:
            return 0.0
        value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(self.pressure * self._ds_exact))
        return float(self.space.mesh.comm.allreduce(value))

    def nodal(self) -> tuple[np.ndarray, np.ndarray]:
        """``(nodes, values)``: block indices of ``u``'s space on the boundary and ``p_h`` there."""
        return self._node_of_q[self.dofs], self.pressure.x.array[self.dofs].copy()

    def at_nodes(self, nodes: np.ndarray) -> np.ndarray:
        """``p_h`` at nodes given as block indices of ``u``'s space (local, with ghosts).

        Args:
            nodes: ``(N,)`` local block indices of ``u``'s space on the contact boundary.
        """
        return self.pressure.x.array[self._q_of_node[np.asarray(nodes, dtype=np.int64)]].copy()

    def destroy(self) -> None:
        """Free the PETSc objects."""
        if self._empty:
            return
        self._rhs.destroy()
        self._weights.destroy()
        if self._ksp is not None:
            self._ksp.destroy()
            self._M.destroy()
