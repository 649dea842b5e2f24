"""Surface ties between non-matching meshes (CalculiX ``*TIE``): docs/method.md §19.1.

A :class:`Tie` names a slave surface (nodes) and a master surface (faces) of one mesh, e.g. two
bodies meshed independently. :func:`tie_constraints` ties every slave node to the point of the
master surface it projects onto, ``u_s = Σ_i N_i(ξ) u_i`` (three linear constraints per slave
node), as a :class:`~dolfinx_ntf.parallel.global_constraints.GlobalLinearConstraintBlock` that
:class:`~dolfinx_ntf.ContactProblem` eliminates like any ``*EQUATION`` (its ``constraints``). The
master faces are gathered on every process, each process ties the slave nodes it owns.

With ``adjust`` (ccx's default) the tied slave nodes are first moved onto the master surface: the
mesh geometry changes, so call :func:`tie_constraints` before building the problem. A slave node
farther from the master surface than the position tolerance is an error naming it (ccx leaves it
untied with a warning: ``untied="skip"``).
"""

from __future__ import annotations

from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat, validation
from dolfinx_ntf.fem.surfaces import (
    FacetSurface,
    NodeSurface,
    reference_coordinates,
    resolve_master,
    resolve_slave,
)
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.surface_tie import default_tolerance, project_on_master, tie_rows
from dolfinx_ntf.parallel.global_constraints import GlobalLinearConstraintBlock

__all__ = ["Tie", "TiedNodes", "tie_constraints"]


@dataclass(frozen=True)
class Tie:
    """A tie of a slave surface to a master surface (CalculiX ``*TIE``, tied contact).

    Args:
        slave: The dependent surface: its nodes follow the master surface.
        master: The independent surface (faces).
        position_tolerance: Slave nodes farther than this from the master surface are not tied;
            None (or below 1e-10, as ccx) for ccx's default, 2.5 % of the master faces' mean
            edge length.
        adjust: Move the tied slave nodes onto the master surface first (ccx's default;
            ccx ``ADJUST=NO`` is False).
        untied: ``"error"``: a slave node out of tolerance is a ``ValueError`` naming it;
            ``"skip"``: it is left free (ccx, which lists it in a file).
        name: Label for messages.
    """

    slave: FacetSurface | NodeSurface
    master: FacetSurface
    position_tolerance: float | None = None
    adjust: bool = True
    untied: str = "error"
    name: str = "tie"

    def __post_init__(self) -> None:
        """Check the arguments (``TypeError`` / ``ValueError`` naming the tie)."""
        label = f"Tie {self.name!r}"
        validation.check_type(self.slave, (FacetSurface, NodeSurface), f"{label}: slave")
        validation.check_type(self.master, FacetSurface, f"{label}: master")
        validation.check_positive(
            self.position_tolerance, f"{label}: position_tolerance", allow_none=True
        )
        if self.untied not in ("error", "skip"):
            raise ValueError(f"{label}: untied must be 'error' or 'skip', got {self.untied!r}")


@dataclass(frozen=True)
class TiedNodes:
    """What :func:`~dolfinx_ntf.tie_constraints` did on this process (for reports and tests).

    Attributes:
        slaves: ``(S,)`` global block dofs of the slave nodes tied here.
        distance: ``(S,)`` their distance to the master surface before any adjustment.
        untied: ``(U,)`` global block dofs of this process's slave nodes left free.
        tolerance: The position tolerance used.
    """

    slaves: np.ndarray
    distance: np.ndarray
    untied: np.ndarray
    tolerance: float


def tie_constraints(
    V: dolfinx.fem.FunctionSpace, tie: Tie
) -> tuple[list[GlobalLinearConstraintBlock], TiedNodes]:
    """The constraints of ``tie`` on ``V`` (and ADJUST's move of the mesh). Collective.

    Args:
        V: The vector displacement space (Lagrange; with ``adjust``, of the geometry's degree).
        tie: The tie.

    Returns:
        ``(constraints, tied)``: the constraints for ``ContactProblem(constraints=...)`` (no
        block when nothing is tied) and the :class:`TiedNodes` of this process.

    Raises:
        ValueError: on every process, for a slave node out of tolerance (``untied="error"``),
            naming its global node number and position; or for ``adjust`` on a space whose nodes
            are not the geometry's.
    """
    validation.check_type(tie, Tie, "tie_constraints: tie")
    comm = V.mesh.comm
    label = f"tie {tie.name!r}"
    index_map = V.dofmap.index_map
    num_local = index_map.size_local + index_map.num_ghosts
    to_global = np.asarray(
        index_map.local_to_global(np.arange(num_local, dtype=np.int32)), dtype=np.int64
    )
    X = reference_coordinates(V)
    faces = resolve_master(V, tie.master, f"{label}: master")
    slave = resolve_slave(V, tie.slave, f"{label}: slave")
    # the master surface on every process, in global node numbers
    face_ids = to_global[faces.faces]
    parts = comm.allgather((face_ids, X[faces.faces]))
    face_ids = np.vstack([p[0] for p in parts])
    face_x = np.vstack([p[1] for p in parts])
    face_ids, first = np.unique(face_ids, axis=0, return_index=True)
    face_x = face_x[first]
    ids, compact = np.unique(face_ids, return_inverse=True)
    compact = compact.reshape(face_ids.shape)
    coords = np.zeros((ids.size, 3))
    coords[compact.ravel()] = face_x.reshape(-1, 3)
    face_type = faces.face_type
    master = MasterSurface(face_type, compact, name=f"{label}: master", coords=coords)
    tolerance = tie.position_tolerance
    if tolerance is None or tolerance < 1e-10:
        tolerance = default_tolerance(face_type, compact, coords)
    owned = slave.nodes[slave.nodes < index_map.size_local]
    projection = project_on_master(master, coords, X[owned], tolerance)
    tied = projection.tied
    untied = to_global[owned[~tied]]
    missing = comm.allgather((untied, X[owned[~tied]]))
    all_untied = np.concatenate([m[0] for m in missing])
    if all_untied.size and tie.untied == "error":
        where = np.vstack([m[1] for m in missing])
        shown = ", ".join(
            f"{int(n)} at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g})"
            for n, x in zip(all_untied[:5], where[:5])
        )
        raise ValueError(
            f"{label}: {all_untied.size} slave node(s) have no master face within the position "
            f"tolerance {tolerance:.6g}: node(s) {shown}{' ...' if all_untied.size > 5 else ''} "
            "(global node numbers; raise position_tolerance, or untied='skip' to leave them free)"
        )
    slaves_global = to_global[owned[tied]]
    face_nodes = ids[compact[projection.face[tied]]]
    # a slave node that is a node of its own master face (a shared node) is tied already
    own = np.any(face_nodes == slaves_global[:, None], axis=1)
    rows = tie_rows(slaves_global[~own], face_nodes[~own], projection.weights[tied][~own])
    if tie.adjust:
        _adjust(V, to_global, owned[tied], projection.points[tied], label)
    report = TiedNodes(slaves_global, projection.distance[tied], untied, tolerance)
    if comm.allreduce(int(rows[0].shape[0]), op=MPI.SUM) == 0:
        return [], report
    block = GlobalLinearConstraintBlock(*rows, name=f"*TIE {tie.name}", drop_prescribed=True)
    return [block], report


def _adjust(
    V: dolfinx.fem.FunctionSpace,
    to_global: np.ndarray,
    nodes: np.ndarray,
    points: np.ndarray,
    label: str,
) -> None:
    """Move the mesh nodes at local block dofs ``nodes`` (owned) to ``points``, ghosts too."""
    mesh = V.mesh
    comm = mesh.comm
    cells = mesh.topology.index_map(mesh.topology.dim)
    num_cells = cells.size_local + cells.num_ghosts
    geometry = compat.geometry_dofs(mesh)[:num_cells]
    space = compat.cell_dofs(V)[:num_cells]
    error = None
    if geometry.shape != space.shape:
        error = ValueError(
            f"{label}: adjust moves mesh nodes, but the space's nodes are not the geometry's "
            "(use Lagrange of the mesh's degree, or adjust=False)"
        )
    validation.raise_collectively(comm, error)
    moved = comm.allgather((to_global[nodes], points))
    ids = np.concatenate([m[0] for m in moved])
    if ids.size == 0:
        return
    new = np.vstack([m[1] for m in moved])
    order = np.argsort(ids)
    ids, new = ids[order], new[order]
    dof_node = np.full(to_global.size, -1, dtype=np.int64)
    dof_node[space.ravel()] = geometry.ravel()
    pos = np.minimum(np.searchsorted(ids, to_global), max(ids.size - 1, 0))
    hit = np.flatnonzero((ids[pos] == to_global) & (dof_node >= 0))
    mesh.geometry.x[dof_node[hit], :3] = new[pos[hit]]
