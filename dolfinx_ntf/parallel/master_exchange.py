"""Large master surfaces exchanged by bounding boxes instead of allgathered (docs/method.md §14.8).

Above :data:`EXCHANGE_ABOVE_FACES` faces a master surface is not gathered whole on every process
(§14.1). Each process asks, by one allgather of a box per process, for the master faces near its
own slave nodes, and receives them from the processes holding them by one ``Alltoallv``: its
*patch*. Its search must find what the whole surface would give, so the patch holds

- the *core*: every face whose box meets the process's request box (the box of its slave nodes
  grown by a margin); the walk of docs/method.md §3.2 runs on core triangles only;
- a *ring* around it: every face within one face size of the request box, so that every node of a
  core face has all its faces (complete nodal normals, hence exact bounding planes); a walk that
  steps onto a ring triangle ends with ``NOT_HELD``, never with "no face";
- the process's own faces elsewhere, for the set-up checks only (not searched);

and at every pairing each process checks, for every node whose walk starts at the nearest
centroid, that no centroid outside its core can be as near (the ball around the node through its
nearest centroid, grown by the tie width and by the largest motion of any master node since the
exchange, lies inside the request box). A node that fails the check or walks off the core makes
every process exchange again, at the current positions, with a grown margin; faces are only ever
added, so face numbers held by springs and friction states stay valid.
"""

from __future__ import annotations

import typing

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import validation
from dolfinx_ntf.fem.surfaces import SlaveSurface, SurfaceFaces
from dolfinx_ntf.kernels import springs
from dolfinx_ntf.kernels.faces import FaceType
from dolfinx_ntf.kernels.master import ContactMaster
from dolfinx_ntf.kernels.search import NOT_HELD, TIE_DIGITS, MasterSurface
from dolfinx_ntf.kernels.tie_frame import TieFrame, triangle_moments
from dolfinx_ntf.parallel.collectives import alltoallv, checkpoint
from dolfinx_ntf.parallel.halo import NodeHalo
from dolfinx_ntf.parallel.surface_distribution import distribute_slave

__all__ = [
    "EXCHANGE_ABOVE_FACES",
    "MARGIN",
    "MasterPatch",
    "distribute_pair",
    "enlarge",
    "uses_exchange",
]

#: Master surfaces of more faces than this (summed over the processes) are exchanged by bounding
#: boxes; smaller ones are allgathered (docs/method.md §14.2, §14.8).
EXCHANGE_ABOVE_FACES = 200_000
#: Growth of a process's request box beyond its slave nodes, in largest master face diagonals.
MARGIN = 2.0


def uses_exchange(comm: MPI.Comm, faces: SurfaceFaces) -> bool:
    """Whether a master surface is exchanged by bounding boxes (above the threshold). Collective."""
    return comm.size > 1 and comm.allreduce(int(faces.faces.shape[0])) > EXCHANGE_ABOVE_FACES


def _largest(comm: MPI.Comm, values: np.ndarray) -> np.ndarray:
    """Elementwise maximum of ``values`` over the processes. Collective."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    out = np.empty_like(values)
    comm.Allreduce(values, out, op=MPI.MAX)
    return out


def _meets(lo: np.ndarray, hi: np.ndarray, box_lo: np.ndarray, box_hi: np.ndarray) -> np.ndarray:
    """Which boxes ``[lo, hi]`` (F, 3) meet the box ``[box_lo, box_hi]``."""
    return np.all(hi >= box_lo, axis=1) & np.all(lo <= box_hi, axis=1)


class MasterPatch(springs.MeshedMasterSprings):
    """The part of a master surface one process searches, with the checks of §14.8.

    Plays the :class:`~dolfinx_ntf.kernels.master.ContactMaster` role like a
    :class:`MasterSurface`; ``update``, ``surface_moments`` and :meth:`exchange` are collective.

    Args:
        halo: The problem's node halo (received nodes are appended to it).
        own: This process's faces of the surface (its cells), in ``V``'s local numbering.
        slave_nodes: The slave nodes whose walks this patch serves (extended indices).
        coords: Current coordinates of the local nodes at least.
        name: Surface name for messages.
    """

    #: ``update`` and ``surface_moments`` are collective; a search may need :func:`enlarge`.
    collective = True

    def __init__(
        self,
        halo: NodeHalo,
        own: SurfaceFaces,
        slave_nodes: np.ndarray,
        coords: np.ndarray,
        name: str,
    ) -> None:
        self.comm: MPI.Comm = halo.comm
        self.name = name
        self._halo = halo
        self._face_type: FaceType = own.face_type
        self._own = own.faces
        self._own_global = halo.local_global[own.faces]
        self._own_nodes = np.unique(own.faces)
        self._slave_nodes = np.asarray(slave_nodes, dtype=np.int64)
        #: This patch's faces (extended numbering; facets -1 where another process holds them).
        self.faces = SurfaceFaces(own.face_type, own.faces.astype(np.int32), own.facets)
        self._global = self._own_global.astype(np.int64)
        self._core = np.zeros(own.faces.shape[0], dtype=bool)
        self._received = np.zeros(own.faces.shape[0], dtype=bool)  # core or ring
        self.surface: MasterSurface | None = None
        self.margin = 0.0
        self.complete = False
        #: Exchanges so far (1 after set-up; each enlargement adds one).
        self.exchanges = 0
        self._need = 0.0  # the margin the last failed checks ask for
        self._walked_off = False
        self._distance = 0.0
        self._eps = 0.0
        total = self.comm.allreduce(int(own.faces.shape[0]))
        if total == 0:
            raise ValueError(f"{name}: the master surface has no faces")
        self.exchange(coords, None)

    # -- exchange ----------------------------------------------------------------------------------

    def exchange(self, coords: np.ndarray, margin: float | None) -> None:
        """Receive the faces near this process's slave nodes at ``coords``. Collective.

        ``margin``: growth of this process's request box (None: :data:`MARGIN` face diagonals).
        """
        comm = self.comm
        n = self._face_type.num_nodes
        x = coords[self._own]  # (F, n, 3)
        lo = x.min(axis=1) if x.size else np.empty((0, 3))
        hi = x.max(axis=1) if x.size else np.empty((0, 3))
        h_local = float(np.linalg.norm(hi - lo, axis=1).max()) if lo.size else 0.0
        extent = np.concatenate(
            [[h_local], -lo.min(axis=0), hi.max(axis=0)]
            if lo.size
            else [[0.0], np.full(6, -np.inf)]
        )
        extent = _largest(comm, extent)
        h, surface_lo, surface_hi = extent[0], -extent[1:4], extent[4:7]
        self._h = float(h)
        if margin is None:
            margin = MARGIN * h
        self.margin = float(margin)
        points = coords[self._slave_nodes]
        if points.size:
            box = np.stack([points.min(axis=0) - margin, points.max(axis=0) + margin])
        else:
            box = np.stack([np.full(3, np.inf), np.full(3, -np.inf)])  # asks for nothing
        boxes = np.asarray(comm.allgather(box))  # (P, 2, 3)
        nodes, refs = [], []
        reference = self._halo.reference
        for q in range(comm.size):
            near = _meets(lo, hi, boxes[q, 0] - h, boxes[q, 1] + h)
            core = _meets(lo, hi, boxes[q, 0], boxes[q, 1])[near]
            nodes.append(np.column_stack([self._own_global[near], core]).ravel())
            refs.append(reference[self._own[near]].ravel())
        g = alltoallv(comm, nodes, np.int64, MPI.INT64_T).reshape(-1, n + 1)
        xr = alltoallv(comm, refs, np.float64, MPI.DOUBLE).reshape(-1, n, 3)
        self._merge(g[:, :n], xr, g[:, n].astype(bool))
        self._region = box
        self._baseline = coords[self._own_nodes].copy()
        self.complete = bool(np.all(box[0] <= surface_lo) and np.all(box[1] >= surface_hi))
        self.exchanges += 1
        self._build()

    def _merge(self, g: np.ndarray, x: np.ndarray, core: np.ndarray) -> None:
        """Add the received faces not held yet (appended: face numbers stay), OR the core flags."""
        old = self._global.shape[0]
        if g.shape[0] == 0:
            return
        key = np.sort(np.vstack([self._global, g]), axis=1)
        _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
        inverse = inverse.ravel()
        merged = np.zeros(first.size, dtype=bool)
        np.logical_or.at(merged, inverse, np.concatenate([self._core, core]))
        held = np.zeros(first.size, dtype=bool)
        held[inverse[:old]] = True
        got = np.zeros(first.size, dtype=bool)
        got[inverse[old:]] = True
        new = np.sort(first[~held]) - old  # rows of g, in order of arrival
        self._core = merged[inverse[:old]]
        self._received |= got[inverse[:old]]
        if new.size:
            local = self._halo.local(g[new], x[new]).astype(np.int32)
            faces = np.vstack([self.faces.faces, local])
            facets = np.concatenate([self.faces.facets, np.full(new.size, -1, np.int32)])
            self.faces = SurfaceFaces(self._face_type, faces, facets)
            self._global = np.vstack([self._global, g[new]])
            self._core = np.concatenate([self._core, merged[inverse[old + new]]])
            self._received = np.concatenate([self._received, np.ones(new.size, dtype=bool)])

    def _build(self) -> None:
        """The search surface on the core and ring faces; ring triangles are not walked on.

        The process's own faces elsewhere stay out of it (no update, no search).
        """
        self.surface = None
        self._held = np.flatnonzero(self._received)  # surface face -> patch face
        self._surface_face = np.full(self.faces.faces.shape[0], -1, dtype=np.int64)
        self._surface_face[self._held] = np.arange(self._held.size)
        if self._held.size == 0:
            return
        core = self._core[self._held] | self.complete
        faces = self.faces.faces[self._held]
        self.surface = MasterSurface(self._face_type, faces, name=self.name)
        self._core_triangle = core[self.surface.triangle_faces]
        self.surface.mark_not_held(np.flatnonzero(~self._core_triangle))

    # -- the MasterSurface interface ---------------------------------------------------------------

    def update(self, coords: np.ndarray) -> None:
        """Update the patch at ``coords``; the whole surface's extent and motion. Collective."""
        self._coords = coords
        x = coords[self._own_nodes]
        if x.size:
            moved = float(np.linalg.norm(x - self._baseline, axis=1).max())
            local = np.concatenate([[moved], -x.min(axis=0), x.max(axis=0)])
        else:
            local = np.concatenate([[0.0], np.full(6, -np.inf)])
        values = _largest(self.comm, local)
        origin, top = -values[1:4], values[4:7]
        scale = float((top - origin).max()) or 1.0
        self._distance, self._eps = float(values[0]), 10.0**-TIE_DIGITS * scale
        error = None
        try:  # a degenerate face of one process's patch is an error on all
            if self.surface is not None:
                self.surface.update(coords, extent=(origin, scale))
        except ValueError as exc:
            error = exc
        validation.raise_collectively(self.comm, error)

    def locate(
        self,
        points: np.ndarray,
        tolerances: np.ndarray | float,
        *,
        max_depth: float | None = None,
        start_faces: np.ndarray | None = None,
        tie_frame: TieFrame | None = None,
        ccx_ties: bool = False,
    ) -> np.ndarray:
        """:meth:`MasterSurface.locate` on the patch; ``NOT_HELD`` where the patch cannot tell."""
        points = np.asarray(points, dtype=float)
        n = points.shape[0]
        tolerances = np.broadcast_to(np.asarray(tolerances, dtype=float), (n,))
        self._need, self._walked_off = 0.0, False
        out = np.full(n, NOT_HELD, dtype=np.int64)
        if self.surface is None:
            self._walked_off = n > 0
            return out
        start = np.full(n, -1, dtype=np.int64)
        if start_faces is not None:  # a face found before: a core face, in the surface
            start_faces = np.asarray(start_faces, dtype=np.int64)
            start = np.where(start_faces >= 0, self._surface_face[np.maximum(start_faces, 0)], -1)
        good = np.ones(n, dtype=bool)
        if not self.complete:
            pending = np.flatnonzero(start < 0)
            if pending.size:
                p = points[pending]
                r, t = self.surface.nearest_centroid(p)
                inside = np.minimum(p - self._region[0], self._region[1] - p).min(axis=1)
                need = r * (1.0 + 1e-12) + 2.0 * self._eps + self._distance
                bad = ~((need <= inside) & self._core_triangle[t])
                good[pending[bad]] = False
                if np.any(bad):
                    self._need = float(need[bad].max())
        found = self.surface.locate(
            points[good],
            tolerances[good],
            max_depth=max_depth,
            start_faces=start[good],
            tie_frame=tie_frame,
            ccx_ties=ccx_ties,
        )
        out[good] = np.where(found >= 0, self._held[np.maximum(found, 0)], found)
        self._walked_off = bool(np.any(found == NOT_HELD))
        return out

    def surface_moments(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`MasterSurface.surface_moments` of the whole surface. Collective.

        Each process adds those of its own faces (each face counts once), so the stable search's
        tie frame (docs/method.md §3.2) is that of the gathered surface.
        """
        triangles = self._own[:, np.asarray(self._face_type.triangles)].reshape(-1, 3)
        a, b, c = (self._coords[triangles[:, k]] for k in range(3))
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        sums = self.comm.allreduce(np.concatenate([[area.sum()], area @ ((a + b + c) / 3.0)]))
        origin = sums[1:] / sums[0]
        return origin, self.comm.allreduce(triangle_moments(a, b, c, origin))

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """See :meth:`MasterSurface.face_patches`."""
        if self.surface is None:
            return np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64)
        which, patch = self.surface.face_patches(self._surface_face[np.asarray(faces)])
        return which, self._held[patch]

    # -- enlargement -------------------------------------------------------------------------------

    def next_margin(self, unresolved: bool) -> float:
        """The margin of the next exchange: what the failed checks ask for, at least doubled."""
        if not unresolved:
            return self.margin
        margin = max(self.margin, 1.25 * self._need)
        if self._walked_off:
            margin = max(margin, 2.0 * self.margin, self._h)
        return margin


def distribute_pair(
    halo: NodeHalo,
    u: dolfinx.fem.Function,
    surface: object,
    slave: SlaveSurface,
    master: SurfaceFaces,
    what: str,
) -> tuple[SlaveSurface, MasterPatch]:
    """A pair's slave surface as :func:`parallel.distribute_pair` gives it, and the master patch.

    Collective; ``master``: this process's faces of the master surface.
    """
    slave = distribute_slave(u.function_space, halo, surface, slave, what)
    coords = halo.reference[: halo.num_local] + u.x.array.reshape(-1, 3)
    return slave, MasterPatch(halo, master, slave.nodes, coords, f"{what} master")


#: Exchanges of one patch after which an enlargement that still does not suffice is an error.
MAX_EXCHANGES = 64


def enlarge(
    master: ContactMaster, face: np.ndarray, coordinates: typing.Callable[[], np.ndarray]
) -> bool:
    """Exchange a pair's master patch again if a search on any process could not tell. Collective.

    Args:
        master: The pair's master surface; only a :class:`MasterPatch` can grow.
        face: The search result of this process (``NOT_HELD`` where the patch could not tell).
        coordinates: Gives the current node coordinates (a collective call), asked for only when
            the patch grows.

    Returns:
        Whether the patch grew: the caller's halo then holds new nodes (its numbering must follow)
        and ``master.faces`` more faces; search again. Always False for a whole master surface.
    """
    if not isinstance(master, MasterPatch):
        return False
    patch = master
    checkpoint(patch.comm)  # a search that failed on one process fails on all (§14.4)
    unresolved = bool(np.any(face == NOT_HELD))
    if not patch.comm.allreduce(unresolved, op=MPI.LOR):
        return False
    if patch.exchanges >= MAX_EXCHANGES:  # the same count on every process
        raise RuntimeError(
            f"{patch.name}: the master surface near the slave nodes is still incomplete after "
            f"{patch.exchanges} exchanges (docs/method.md §14.8)"
        )
    margin = patch.next_margin(unresolved)
    checkpoint(patch.comm)
    patch.exchange(coordinates(), margin)
    checkpoint(patch.comm)
    return True
