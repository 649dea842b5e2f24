"""Contact surfaces across MPI processes: which faces each process gathers.

docs/method.md §14.1, §14.2. The surfaces are distributed once, at setup: the master surface is
allgathered (or exchanged by bounding boxes, ``master_exchange``); each slave face goes only to the
processes owning one of its nodes, so a process's share grows with its own part of the slave
surface. Each spring lives on the process owning its slave node, so it is evaluated once; the
pure-numpy kernels run unchanged on the halo's extended numbering, and the same master surface on
every process makes the pairing independent of the partition.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf.fem.surfaces import (
    NodeSurface,
    SlaveSurface,
    SurfaceFaces,
    boundary_faces,
    faces_touching,
)
from dolfinx_ntf.parallel.collectives import alltoallv, send_to_owners
from dolfinx_ntf.parallel.halo import NodeHalo

__all__ = ["distribute_master", "distribute_pair", "distribute_slave"]


def _gather_faces(
    halo: NodeHalo, faces: SurfaceFaces, what: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All processes' faces of a surface: global nodes, reference coordinates, this process's facet.

    Duplicates (faces of ghost cells) are dropped; the order is the same on every process. The
    facet is -1 where the face's cell is not on this process.
    """
    comm = halo.comm
    g = halo.local_global[faces.faces]
    x = halo.reference[faces.faces]
    parts = comm.allgather((g, x))
    n = faces.faces.shape[1]
    all_g = np.vstack([p[0].reshape(-1, n) for p in parts]).astype(np.int64)
    all_x = np.vstack([p[1].reshape(-1, n, 3) for p in parts])
    key = np.sort(all_g, axis=1)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    facets = np.full(first.size, -1, dtype=np.int32)
    start = sum(p[0].shape[0] for p in parts[: comm.rank])
    facets[inverse[start : start + faces.faces.shape[0]]] = faces.facets
    return all_g[first], all_x[first], facets


def _marked_at_owners(halo: NodeHalo, nodes: np.ndarray) -> np.ndarray:
    """Which owned nodes any process lists in its ``nodes`` (local indices). Collective.

    Each process sends the global numbers of its listed ghosts to their owners.
    """
    nodes = np.asarray(nodes, dtype=np.int64)
    marked = np.zeros(halo.num_owned, dtype=bool)
    marked[nodes[nodes < halo.num_owned]] = True
    ghosts = halo.local_global[nodes[nodes >= halo.num_owned]]
    received = send_to_owners(halo.comm, ghosts, halo.owner(ghosts))
    marked[received - halo.first_nodes[halo.comm.rank]] = True
    return marked


def _marked_locally(V: dolfinx.fem.FunctionSpace, halo: NodeHalo, owned: np.ndarray) -> np.ndarray:
    """``owned`` (a flag per owned node) at every local node (ghosts from owners). Collective."""
    marker = dolfinx.fem.Function(V)
    marker.x.array[:] = 0.0
    bs = halo.bs  # one flag per node: its first component
    marker.x.array[: bs * halo.num_owned : bs] = owned
    marker.x.scatter_forward()
    return marker.x.array[: bs * halo.num_local : bs] > 0.5


def _exterior_faces_touching(
    V: dolfinx.fem.FunctionSpace, marked: np.ndarray, what: str
) -> SurfaceFaces:
    """This process's exterior faces with a corner among the ``marked`` local nodes."""
    mesh = V.mesh
    mesh.topology.create_connectivity(mesh.topology.dim - 1, mesh.topology.dim)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    faces = boundary_faces(V, exterior, what=what)
    touching = marked[faces.faces[:, : faces.face_type.num_corners]].any(axis=1)
    return SurfaceFaces(faces.face_type, faces.faces[touching], faces.facets[touching])


def _unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(rows, axis=0, return_index=True, return_inverse=True)[1:]``, by a lexsort.

    The first occurrence of every distinct row, in the rows' lexicographic order, and the index
    of every row among them.
    """
    order = np.lexsort(rows.T[::-1])  # stable: equal rows keep their order
    ordered = rows[order]
    new = np.ones(rows.shape[0], dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    inverse = np.empty(rows.shape[0], dtype=np.int64)
    inverse[order] = np.cumsum(new) - 1
    return order[new], inverse


def _send_faces_to_owners(halo: NodeHalo, faces: SurfaceFaces) -> tuple[np.ndarray, np.ndarray]:
    """Send each face to the other processes owning one of its nodes, once each. Collective.

    Sends global node numbers and reference coordinates; returns the faces received, in the
    order of the sending processes.
    """
    comm, n = halo.comm, faces.faces.shape[1]
    g = halo.local_global[faces.faces].astype(np.int64)
    owner = np.sort(halo.owner(g), axis=1)
    once = np.ones(owner.shape, dtype=bool)  # each owner once per face
    once[:, 1:] = owner[:, 1:] != owner[:, :-1]
    once &= owner != comm.rank  # this process's own faces stay here
    to = owner[once]
    face = np.repeat(np.arange(g.shape[0]), n).reshape(-1, n)[once]
    order = np.argsort(to, kind="stable")  # by owner, then the faces in their order
    to, face = to[order], face[order]
    split = np.searchsorted(to, np.arange(1, comm.size))
    nodes = [p.ravel() for p in np.split(g[face], split)]
    x = [p.ravel() for p in np.split(halo.reference[faces.faces[face]], split)]
    received_g = alltoallv(comm, nodes, np.int64, MPI.INT64_T).reshape(-1, n)
    received_x = alltoallv(comm, x, np.float64, MPI.DOUBLE).reshape(-1, n, 3)
    return received_g, received_x


def distribute_pair(
    V: dolfinx.fem.FunctionSpace,
    halo: NodeHalo,
    surface: object,
    slave: SlaveSurface,
    master: SurfaceFaces,
    what: str,
) -> tuple[SlaveSurface, SurfaceFaces]:
    """A pair's surfaces as this process needs them, in the halo's extended numbering. Collective.

    The master: every face of every process. The slave: the slave nodes this process owns, and
    every slave face (of any process) holding one of them, so that spring areas are complete at
    partition cuts (docs/method.md §14.1).
    """
    master = distribute_master(halo, master, f"{what} master")
    return distribute_slave(V, halo, surface, slave, what), master


def distribute_master(halo: NodeHalo, master: SurfaceFaces, what: str) -> SurfaceFaces:
    """Every master face of every process, in the halo's extended numbering. Collective.

    Args:
        halo: The problem's node halo (the gathered faces' nodes are appended to it).
        master: This process's master faces (one face type).
        what: Label for messages.
    """
    g, x, facets = _gather_faces(halo, master, what)
    return SurfaceFaces(master.face_type, halo.local(g, x).astype(np.int32), facets)


def distribute_slave(
    V: dolfinx.fem.FunctionSpace,
    halo: NodeHalo,
    surface: object,
    slave: SlaveSurface,
    what: str,
) -> SlaveSurface:
    """The slave nodes this process owns and every slave face holding one of them. Collective.

    For :func:`distribute_pair`, and alone for a rigid master (no master nodes, docs/method.md
    §14.6).
    """
    comm = halo.comm
    mine = _marked_at_owners(halo, slave.nodes)  # owned nodes some process lists as slave
    groups = slave.face_groups  # C3D15: triangles beside quadrilaterals, per type (§38)
    if isinstance(surface, NodeSurface) and surface.exterior is not None:  # C3D15 (§38)
        marked = _marked_locally(V, halo, mine)
        exterior = surface.exterior.face_groups(V, f"{what} slave")
        groups = tuple(faces_touching(g, marked) for g in exterior)
    elif isinstance(surface, NodeSurface):  # vertices given on one process touch faces of others
        faces = _exterior_faces_touching(V, _marked_locally(V, halo, mine), f"{what} slave")
        if faces.face_type is not slave.faces.face_type:  # C3D20: quad9 facets as quad8 (§13.5)
            n = slave.faces.face_type.num_nodes
            faces = SurfaceFaces(slave.faces.face_type, faces.faces[:, :n], faces.facets)
        groups = (faces,)
    slave_faces, *more = (_faces_at_owners(halo, group, mine) for group in groups)
    nodes = np.flatnonzero(mine)
    faceless = None  # midside nodes of a node-based surface (docs/method.md §13.5, §14.10)
    marked = slave.nodes[slave.faceless] if slave.faceless is not None else slave.nodes[:0]
    if comm.allreduce(int(marked.size), op=MPI.MAX):
        faceless = _marked_at_owners(halo, marked)[nodes]
    return SlaveSurface(nodes, slave_faces, faceless, more_faces=tuple(more))


def _faces_at_owners(halo: NodeHalo, faces: SurfaceFaces, mine: np.ndarray) -> SurfaceFaces:
    """Every process's ``faces`` holding one of the ``mine`` owned nodes, extended. Collective."""
    g, x = _send_faces_to_owners(halo, faces)
    # the faces received and this process's own (for their facets); duplicates dropped, sorted
    g = np.vstack([g, halo.local_global[faces.faces]])
    x = np.vstack([x, halo.reference[faces.faces]])
    first, inverse = _unique_rows(np.sort(g, axis=1))
    facets = np.full(first.size, -1, dtype=np.int32)
    facets[inverse[g.shape[0] - faces.faces.shape[0] :]] = faces.facets
    g, x = g[first], x[first]
    keep = np.isin(g, halo.local_global[: halo.num_owned][mine]).any(axis=1)
    return SurfaceFaces(
        faces.face_type, halo.local(g[keep], x[keep]).astype(np.int32), facets[keep]
    )
