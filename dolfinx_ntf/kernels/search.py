"""Master triangulation, nodal normals, bounding planes and the triangle walk.

The method is described in docs/method.md §2.3 and §3.2.

Each master face is split into the sub-triangles of its `FaceType`. At every pairing the surface is
updated in the current configuration: averaged nodal normals, one bounding plane per triangle edge
(shared exactly by the two triangles of an interior edge, so the prisms tile space without gaps)
and a k-d tree of triangle centroids. A slave node is then located by walking from the triangle
with the nearest centroid across violated bounding planes, as CalculiX does.

Pure numpy/scipy; nodes are integer ids indexing rows of a coordinate array.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
from scipy.spatial import cKDTree

from dolfinx_ntf.kernels import springs
from dolfinx_ntf.kernels.faces import FaceType
from dolfinx_ntf.kernels.tie_frame import TieFrame, triangle_moments

__all__ = ["MAX_WALK_STEPS", "NOT_HELD", "MasterFaceGroup", "MasterSurface"]

MAX_WALK_STEPS = 100
"""A walk taking more steps than this finds no face (docs/method.md §3.2)."""
TIE_DIGITS = 9
"""Centroid distances equal to this many digits of the surface size are ties."""
TIE_CANDIDATES = 8
"""Nearest centroids compared for ties (the most triangles around a node of a regular mesh)."""
NOT_HELD = -2
"""Neighbour and walk result where the surface continues on triangles not held here (§14.8)."""


class MasterSurface(springs.MeshedMasterSprings):
    """Triangulated master surface with the search prisms of docs/method.md §2.3.

    Args:
        face_type: Type of all faces of the surface.
        faces: (F, n) node ids of the faces, in CalculiX order (outward normal).
        name: Surface name used in error messages.
        coords: Optional (num_nodes, 3) coordinates. When given, error messages about invalid
            edges include the node coordinates, and `update(coords)` is run at construction.
        more: Faces of other types ``((face_type, faces), ...)`` on the same surface (a C3D15
            master of triangles and quadrilaterals, docs/method.md §38.8): one triangulation
            and one search over all; their faces are numbered after ``faces``, group by group
            (:attr:`face_groups`).

    Raises:
        ValueError: If `faces` is malformed, if a face edge is shared by more than two faces, or
            if two faces sharing an edge are oriented inconsistently (edge used twice in the same
            direction).
    """

    #: A search here involves this process only (the :class:`~dolfinx_ntf.kernels.master.
    #: ContactMaster` role).
    collective = False

    def __init__(
        self,
        face_type: FaceType,
        faces: np.ndarray,
        *,
        name: str = "master",
        coords: np.ndarray | None = None,
        more: tuple[tuple[FaceType, np.ndarray], ...] = (),
    ) -> None:
        self._face_type = face_type
        self._name = name
        groups = [(face_type, _check_faces(face_type, faces, name))]
        for more_type, more_faces in more:  # docs/method.md §38.8: one search over both kinds
            if np.asarray(more_faces).size:
                groups.append((more_type, _check_faces(more_type, more_faces, name)))
        self._groups = tuple(groups)
        sizes = [g.shape[0] for _, g in groups]
        self._group_offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        faces = groups[0][1] if len(groups) == 1 else _padded_faces(groups)
        self._faces = faces
        self._nodes = np.unique(np.concatenate([g.ravel() for _, g in groups]))
        #: per group: (F_g, n_g) master-local node indices of its faces
        self._local_groups = tuple(np.searchsorted(self._nodes, g) for _, g in groups)
        self._local_faces = self._local_groups[0] if len(groups) == 1 else None
        ref = None if coords is None else np.asarray(coords, dtype=float)

        face_edges, face_of_edge, corner_faces, corner_nodes = [], [], [], []
        triangles, local_triangles, triangle_faces, degenerate = [], [], [], []
        for (ft, g), local, offset in zip(groups, self._local_groups, self._group_offsets):
            nc = ft.num_corners
            corners = g[:, :nc]
            face_edges.append(
                np.stack([corners, np.roll(corners, -1, axis=1)], axis=2).reshape(-1, 2)
            )
            face_of_edge.append(offset + np.repeat(np.arange(g.shape[0]), nc))
            corner_faces.append(offset + np.repeat(np.arange(g.shape[0]), nc))
            corner_nodes.append(local[:, :nc].ravel())
            tri_local = np.asarray(ft.triangles, dtype=np.int64)
            t_per_face = tri_local.shape[0]
            tri = g[:, tri_local].reshape(-1, 3)
            # ... and one sub-triangle with a repeated node, left out: such a face has one
            # triangle
            kept = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
            if np.any(~kept.reshape(-1, t_per_face).any(axis=1)):
                f = int(np.flatnonzero(~kept.reshape(-1, t_per_face).any(axis=1))[0])
                raise ValueError(
                    f"Master surface '{name}': face {offset + f} ({g[f].tolist()}) has no area"
                )
            degenerate.append(~kept.reshape(-1, t_per_face).all(axis=1))
            triangle_faces.append(offset + np.repeat(np.arange(g.shape[0]), t_per_face)[kept])
            triangles.append(tri[kept])
            local_triangles.append(local[:, tri_local].reshape(-1, 3)[kept])
        face_edges = np.concatenate(face_edges)
        # a quad4 face with a repeated corner (a collapsed wedge's triangle, docs/method.md
        # §30) has a zero-length edge, which borders nothing
        item = groups[0][0].num_corners if len(groups) == 1 else np.concatenate(face_of_edge)
        _group_edges(
            face_edges, item, name, ref, "face", "faces", face_edges[:, 0] != face_edges[:, 1]
        )
        self._degenerate = np.concatenate(degenerate)  # (F,) faces
        self._triangle_faces = np.concatenate(triangle_faces)
        self._first_triangle_of_face = np.searchsorted(
            self._triangle_faces, np.arange(self._group_offsets[-1])
        )
        self._triangles = np.concatenate(triangles)
        self._local_triangles = np.concatenate(local_triangles)
        tri_edges = np.stack(
            [self._triangles, np.roll(self._triangles, -1, axis=1)], axis=2
        ).reshape(-1, 2)
        rep, edge_id, sign, pairs = _group_edges(tri_edges, 3, name, ref, "triangle", "triangles")
        neighbours = np.full(tri_edges.shape[0], -1, dtype=np.int64)
        neighbours[pairs[:, 0]] = pairs[:, 1] // 3
        neighbours[pairs[:, 1]] = pairs[:, 0] // 3
        self._neighbours = neighbours.reshape(-1, 3)
        # Unique edges as (start, end) master-local indices; each triangle edge is one of them,
        # traversed forward (sign +1) or backward (sign -1).
        local_edges = np.stack(
            [self._local_triangles, np.roll(self._local_triangles, -1, axis=1)], axis=2
        ).reshape(-1, 2)
        self._edges = local_edges[rep]
        self._edge_id = edge_id.reshape(-1, 3)
        self._edge_sign = sign.reshape(-1, 3).astype(float)

        corner_faces, corner_nodes = np.concatenate(corner_faces), np.concatenate(corner_nodes)
        incidence = scipy.sparse.csr_matrix(
            (np.ones(corner_faces.size, dtype=np.int8), (corner_faces, corner_nodes)),
            shape=(int(self._group_offsets[-1]), self._nodes.size),
        )
        patches = (incidence @ incidence.T).tocsr()
        patches.sort_indices()
        self._patch_offsets, self._patch_faces = patches.indptr.astype(np.int64), patches.indices

        self._updated = False
        if ref is not None:
            self.update(ref)

    # ------------------------------------------------------------------ properties
    @property
    def name(self) -> str:
        """Surface name used in messages."""
        return self._name

    @property
    def face_type(self) -> FaceType:
        """Type of all faces (of the first group where there are several)."""
        return self._face_type

    @property
    def face_groups(self) -> tuple[tuple[FaceType, np.ndarray], ...]:
        """``(face_type, faces)`` of each face type, in face-number order (one if one type)."""
        return self._groups

    @property
    def group_offsets(self) -> np.ndarray:
        """(G + 1,) the first face number of each group of :attr:`face_groups`, then F."""
        return self._group_offsets

    @property
    def faces(self) -> np.ndarray:
        """(F, n) node ids of the faces (several types: padded with -1 to the widest)."""
        return self._faces

    @property
    def num_faces(self) -> int:
        """Number of master faces F."""
        return int(self._faces.shape[0])

    @property
    def nodes(self) -> np.ndarray:
        """(M,) sorted unique master node ids."""
        return self._nodes

    @property
    def triangles(self) -> np.ndarray:
        """(T, 3) node ids of the sub-triangles, outward order, by face (`triangle_faces`)."""
        return self._triangles

    @property
    def triangle_faces(self) -> np.ndarray:
        """(T,) parent face index of each sub-triangle."""
        return self._triangle_faces

    @property
    def triangle_neighbours(self) -> np.ndarray:
        """(T, 3) triangle across edges (0,1), (1,2), (2,0) of each triangle, -1 for none."""
        return self._neighbours

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The faces sharing a corner with each of ``faces`` (itself included), flattened.

        Returns:
            ``(which, patch)``: ``patch[k]`` touches ``faces[which[k]]``.
        """
        faces = np.asarray(faces, dtype=np.int64)
        starts = self._patch_offsets[faces]
        counts = self._patch_offsets[faces + 1] - starts
        which = np.repeat(np.arange(faces.size), counts)
        position = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        return which, self._patch_faces[np.repeat(starts, counts) + position].astype(np.int64)

    def mark_not_held(self, triangles: np.ndarray) -> None:
        """Walks stepping onto ``triangles`` end with :data:`NOT_HELD` (docs/method.md §14.8).

        For a part of a surface whose ``triangles`` are there for the nodal normals only.
        """
        self._neighbours[np.isin(self._neighbours, np.asarray(triangles))] = NOT_HELD

    @property
    def nodal_normals(self) -> np.ndarray:
        """(M, 3) averaged unit nodal normals, rows aligned with `nodes`."""
        self._require_update()
        return self._nodal_normals

    @property
    def triangle_normals(self) -> np.ndarray:
        """(T, 3) unit normals of the sub-triangle planes (outward)."""
        self._require_update()
        return self._triangle_normals

    @property
    def triangle_centroids(self) -> np.ndarray:
        """(T, 3) centroids of the sub-triangles."""
        self._require_update()
        return self._centroids

    def surface_moments(self) -> tuple[np.ndarray, np.ndarray]:
        """Area moments of the triangulated surface about its area centroid, for `TieFrame`.

        Returns:
            ``(origin, moments)``: the centroid and the moment vector about it
            (``dolfinx_ntf.kernels.tie_frame``).
        """
        self._require_update()
        x = self._current
        a, b, c = (x[self._local_triangles[:, k]] for k in range(3))
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        origin = (area @ self._centroids) / area.sum()
        return origin, triangle_moments(a, b, c, origin)

    # ------------------------------------------------------------------ update
    def update(self, coords: np.ndarray, *, extent: tuple[np.ndarray, float] | None = None) -> None:
        """Recompute normals, bounding planes and the centroid tree for current coordinates.

        Args:
            coords: (num_nodes, 3) current node positions, indexed by node id.
            extent: (lowest corner, largest side) of the box of the whole surface when this object
                holds a part of it (docs/method.md §14.8): ties are judged on the whole surface.

        Raises:
            ValueError: If `coords` has the wrong shape or non-finite master coordinates, or if a
                face normal, nodal normal, triangle or bounding plane is degenerate.
        """
        self._updated = False  # a failed update leaves no half-updated geometry in use
        coords = np.asarray(coords, dtype=float)
        if coords.ndim != 2 or coords.shape[1] != 3 or coords.shape[0] <= self._nodes[-1]:
            raise ValueError(
                f"Master surface '{self._name}': coords must have shape (num_nodes, 3) with "
                f"num_nodes > {self._nodes[-1]} (largest master node id), got {coords.shape}"
            )
        x = coords[self._nodes]
        if not np.all(np.isfinite(x)):
            bad = self._nodes[~np.all(np.isfinite(x), axis=1)][0]
            raise ValueError(f"Master surface '{self._name}': node {bad} has non-finite coords")

        self._nodal_normals = self._compute_nodal_normals(x)
        a, b, c = (x[self._local_triangles[:, k]] for k in range(3))
        self._centroids = ((a + b) + c) / 3.0  # CalculiX's sums (docs/method.md §3.6)
        m = np.cross(b - a, c - a)
        norm = np.linalg.norm(m, axis=1)
        if np.any(norm <= 0.0) or not np.all(np.isfinite(norm)):
            t = int(np.flatnonzero(~(norm > 0.0))[0])
            raise ValueError(
                f"Master surface '{self._name}': degenerate sub-triangle {t} of face "
                f"{self._triangle_faces[t]} (nodes {self._triangles[t].tolist()})"
            )
        self._triangle_normals = m / norm[:, None]
        self._triangle_origins = a
        self._current = x

        # Bounding plane of each unique edge, oriented outward for its forward traversal.
        xs, xe = x[self._edges[:, 0]], x[self._edges[:, 1]]
        t = xe - xs
        t /= np.linalg.norm(t, axis=1)[:, None]
        e = self._nodal_normals[self._edges[:, 0]] + self._nodal_normals[self._edges[:, 1]]
        e -= np.einsum("ij,ij->i", e, t)[:, None] * t
        p = np.cross(t, e)
        pnorm = np.linalg.norm(p, axis=1)  # = |e|, at most 2
        if np.any(~(pnorm > 1e-12)):
            k = int(np.flatnonzero(~(pnorm > 1e-12))[0])
            ids = self._nodes[self._edges[k]].tolist()
            raise ValueError(
                f"Master surface '{self._name}': no bounding plane for edge {ids}: the nodal "
                "normals at its ends cancel or lie along the edge"
            )
        p /= pnorm[:, None]
        sign = self._edge_sign[:, :, None]
        self._plane_normals = sign * p[self._edge_id]  # (T, 3, 3)
        self._plane_points = xs[self._edge_id]  # (T, 3, 3)
        self._tree = cKDTree(self._centroids)
        origin, self._scale = (
            (x.min(axis=0), float(np.ptp(x, axis=0).max()) or 1.0) if extent is None else extent
        )
        rounded = np.round((self._centroids - origin) / self._scale, TIE_DIGITS)
        self._centroid_rank = np.empty(self._centroids.shape[0], dtype=np.int64)
        self._centroid_rank[np.lexsort(rounded.T[::-1])] = np.arange(self._centroids.shape[0])
        self._updated = True

    def _compute_nodal_normals(self, x: np.ndarray) -> np.ndarray:
        """Normalized sum of the unit face normals at each master node's parametric position.

        A face with a repeated corner (a collapsed wedge's triangle) counts once per node with
        its plane's normal, as ccx's 3-node triangle (docs/method.md §30).
        """
        acc = np.zeros((self._nodes.size, 3))
        for (ft, g), local, offset in zip(self._groups, self._local_groups, self._group_offsets):
            dphi = np.asarray(ft.shape_derivatives(np.asarray(ft.node_parameters, dtype=float)))
            xf = x[local]  # (F, n, 3)
            q_xi = np.einsum("fjc,kj->fkc", xf, dphi[:, :, 0])
            q_eta = np.einsum("fjc,kj->fkc", xf, dphi[:, :, 1])
            m = np.cross(q_xi, q_eta)  # (F, n, 3)
            counted = np.ones(local.shape, dtype=bool)
            degenerate = self._degenerate[offset : offset + g.shape[0]]
            if np.any(degenerate):
                faces = np.flatnonzero(degenerate)
                tri = self._local_triangles[np.searchsorted(self._triangle_faces, offset + faces)]
                a, b, c = (x[tri[:, k]] for k in range(3))
                m[faces] = np.cross(b - a, c - a)[:, None, :]
                here = local[faces]
                repeat = np.triu(here[:, :, None] == here[:, None, :], 1).any(axis=1)
                counted[faces] = ~repeat  # a repeated node's later slots
            norm = np.linalg.norm(m, axis=2)
            if np.any(~(norm > 0.0)):
                f, k = (int(v[0]) for v in np.nonzero(~(norm > 0.0)))
                raise ValueError(
                    f"Master surface '{self._name}': face {offset + f} (nodes {g[f].tolist()}) "
                    f"has a zero normal at its node {g[f, k]}"
                )
            unit = m / norm[:, :, None]
            np.add.at(acc, local[counted], unit[counted])
        anorm = np.linalg.norm(acc, axis=1)
        if np.any(~(anorm > 1e-12)):
            k = int(np.flatnonzero(~(anorm > 1e-12))[0])
            raise ValueError(
                f"Master surface '{self._name}': the face normals at node {self._nodes[k]} "
                f"(coords {x[k].tolist()}) cancel, no nodal normal"
            )
        return acc / anorm[:, None]

    # ------------------------------------------------------------------ search
    def plane_distances(self, points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
        """Signed distances of points to the three bounding planes of given triangles.

        Args:
            points: (N, 3) positions.
            triangles: (N,) triangle indices.

        Returns:
            (N, 3) distances to the planes through edges (0,1), (1,2), (2,0); positive outside.
        """
        self._require_update()
        points = np.asarray(points, dtype=float)
        return np.einsum(
            "nkc,nkc->nk",
            self._plane_normals[triangles],
            points[:, None, :] - self._plane_points[triangles],
        )

    def locate(
        self,
        points: np.ndarray,
        tolerances: np.ndarray | float,
        *,
        max_depth: float | None = None,
        max_steps: int = MAX_WALK_STEPS,
        start_faces: np.ndarray | None = None,
        ccx_ties: bool = False,
        tie_frame: TieFrame | None = None,
    ) -> np.ndarray:
        """Master face holding each point, by the triangle walk of docs/method.md §3.2.

        Args:
            points: (N, 3) current slave positions.
            tolerances: (N,) or scalar plane tolerance; a plane counts as violated when the
                signed distance exceeds it (ccx: 1e-3*sqrt(A_p), or 0 when A_p = 0).
            max_depth: If given, reject points deeper than this below the accepted triangle's
                plane (not in ccx, which has no penetration-side limit).
            max_steps: A walk needing more steps than this finds nothing (ccx: 100).
            start_faces: Optional (N,) face to start each walk from (its first sub-triangle), -1 for
                the nearest centroid. Starting from the previous face keeps a node on it while it
                stays within the tolerance (not in ccx, whose walk always starts at the nearest
                centroid).
            ccx_ties: Find the nearest centroid as CalculiX does (docs/method.md §3.6) instead of
                breaking ties by position.
            tie_frame: Decide centroids equally near by position in this frame instead of the
                global axes (the stable search, docs/method.md §3.2).

        Returns:
            (N,) face index, or -1 where no face is found (:data:`NOT_HELD` where the walk
            stepped onto a triangle marked by :meth:`mark_not_held`).
        """
        start = None
        if start_faces is not None:
            start_faces = np.asarray(start_faces, dtype=np.int64)
            start = np.where(
                start_faces >= 0, self._first_triangle_of_face[np.maximum(start_faces, 0)], -1
            )
        tri = self.locate_triangles(
            points,
            tolerances,
            max_depth=max_depth,
            max_steps=max_steps,
            start=start,
            tie_frame=tie_frame,
            ccx_ties=ccx_ties,
        )
        out = np.full(tri.shape, -1, dtype=np.int64)
        found = tri >= 0
        out[found] = self._triangle_faces[tri[found]]
        out[tri == NOT_HELD] = NOT_HELD
        return out

    def locate_triangles(
        self,
        points: np.ndarray,
        tolerances: np.ndarray | float,
        *,
        max_depth: float | None = None,
        max_steps: int = MAX_WALK_STEPS,
        start: np.ndarray | None = None,
        ccx_ties: bool = False,
        tie_frame: TieFrame | None = None,
    ) -> np.ndarray:
        """Sub-triangle accepted by the walk for each point (see `locate`); -1 for none.

        Args:
            points: (N, 3) current slave positions.
            tolerances: (N,) or scalar plane tolerance (see `locate`).
            max_depth: Optional penetration-side depth limit (see `locate`).
            max_steps: A walk needing more steps than this finds nothing (ccx: 100).
            start: Optional (N,) start triangle per point; -1 (or None) for the nearest centroid.
            ccx_ties: Nearest centroid as CalculiX finds it (see `locate`).
            tie_frame: Optional frame deciding ties of the nearest centroid (see `locate`).

        Returns:
            (N,) triangle index, or -1. The accepted triangle's normal is the one ADJUST uses
            (ccx's ADJUST, not supported yet).
        """
        self._require_update()
        points, tol = self._check_points(points, tolerances, max_depth)
        if max_steps < 0:
            raise ValueError(f"max_steps = {max_steps} must be >= 0")
        n = points.shape[0]
        result = np.full(n, -1, dtype=np.int64)
        if n == 0:
            return result
        if ccx_ties:
            cur = self._ccx_nearest_centroids(points)
        elif tie_frame is None:
            cur = self._nearest_centroids(points)
        else:
            cur = self._nearest_centroids_in_frame(points, tie_frame)
        if start is not None:
            start = np.asarray(start, dtype=np.int64)
            cur = np.where(start >= 0, start, cur)
        prev = np.full(n, -1, dtype=np.int64)
        idx = np.arange(n)
        hist = np.full((n, 8), -1, dtype=np.int64)  # visited triangles of the walking points
        hist[:, 0] = cur
        for step in range(max_steps + 1):  # `step` = steps taken so far
            violated = self.plane_distances(points[idx], cur) > tol[idx, None]
            moving = violated.any(axis=1)
            result[idx[~moving]] = cur[~moving]
            plane = np.argmax(violated, axis=1)  # first violated plane, in order 1, 2, 3
            nb = self._neighbours[cur, plane]
            result[idx[moving & (nb == NOT_HELD)]] = NOT_HELD  # the walk leaves what is held
            moving &= nb >= 0  # no neighbour: no face
            back = moving & (nb == prev)  # neighbour is the triangle just left: accept
            result[idx[back]] = cur[back]
            moving &= ~back
            moving &= ~np.any(hist[:, : step + 1] == nb[:, None], axis=1)  # visited: no face
            if step == max_steps:
                break  # the walking points would exceed the step limit: no face
            idx, prev, cur, hist = idx[moving], cur[moving], nb[moving], hist[moving]
            if idx.size == 0:
                break
            if step + 1 == hist.shape[1]:
                grow = min(hist.shape[1], max_steps + 1 - hist.shape[1])
                hist = np.concatenate([hist, np.full((idx.size, grow), -1, np.int64)], axis=1)
            hist[:, step + 1] = cur

        if max_depth is not None:
            found = np.flatnonzero(result >= 0)
            t = result[found]
            depth = -np.einsum(
                "nc,nc->n", self._triangle_normals[t], points[found] - self._triangle_origins[t]
            )
            result[found[depth > max_depth]] = -1
        return result

    def _nearest_centroids_in_frame(self, points: np.ndarray, tie_frame: TieFrame) -> np.ndarray:
        """The triangle with the nearest centroid to each point, ties broken in ``tie_frame``.

        Among centroids equally near (to ``10**-TIE_DIGITS`` of the surface size) the first by
        position in the frame (``TieFrame.first``): the same under renumbering and rigid motions
        of the model (the stable search, docs/method.md §3.2).
        """
        k = min(TIE_CANDIDATES, self._centroids.shape[0])
        distance, nearest = self._tree.query(points, k=k)
        distance, nearest = distance.reshape(-1, k), nearest.reshape(-1, k)
        tolerance = 10.0**-TIE_DIGITS * self._scale
        first = tie_frame.first(
            self._centroids[nearest], distance <= distance[:, :1] + tolerance, tolerance
        )
        return nearest[np.arange(nearest.shape[0]), first].astype(np.int64)

    def nearest_centroid(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance to the nearest triangle centroid, and that triangle, of each point (§14.8)."""
        self._require_update()
        distance, triangle = self._tree.query(np.asarray(points, dtype=float).reshape(-1, 3), k=1)
        return distance, triangle.astype(np.int64)

    def _nearest_centroids(self, points: np.ndarray) -> np.ndarray:
        """The triangle with the nearest centroid to each point, ties broken by position.

        Among centroids equally near (to ``10**-TIE_DIGITS`` of the surface size) the first in
        (x, y, z) order, so the choice depends neither on the numbering of nodes and faces nor on
        k-d tree internals.
        """
        k = min(TIE_CANDIDATES, self._centroids.shape[0])
        distance, nearest = self._tree.query(points, k=k)
        distance, nearest = distance.reshape(-1, k), nearest.reshape(-1, k)
        tied = distance <= distance[:, :1] + 10.0**-TIE_DIGITS * self._scale
        rank = np.where(tied, self._centroid_rank[nearest], np.iinfo(np.int64).max)
        return nearest[np.arange(nearest.shape[0]), np.argmin(rank, axis=1)].astype(np.int64)

    def _ccx_nearest_centroids(self, points: np.ndarray) -> np.ndarray:
        """The nearest centroid as CalculiX 2.20 decides ties (docs/method.md §3.6).

        CalculiX compares squared distances ``(dx**2 + dy**2) + dz**2`` in floating point to the
        centroids ``((a + b) + c) / 3`` of the sub-triangles (nodes in their outward order), so a
        geometric tie goes to the centroid its round-off puts nearer. Distances that are equal even
        in floating point are decided by its coordinate-sorted search, which is not reproduced: the
        position order of `_nearest_centroids` decides them.
        """
        k = min(TIE_CANDIDATES, self._centroids.shape[0])
        _, nearest = self._tree.query(points, k=k)
        nearest = nearest.reshape(-1, k)
        d = (self._centroids[nearest] - points[:, None, :]) ** 2
        d2 = (d[:, :, 0] + d[:, :, 1]) + d[:, :, 2]
        tied = d2 == d2.min(axis=1, keepdims=True)
        rank = np.where(tied, self._centroid_rank[nearest], np.iinfo(np.int64).max)
        return nearest[np.arange(nearest.shape[0]), np.argmin(rank, axis=1)].astype(np.int64)

    # ------------------------------------------------------------------ helpers
    def _require_update(self) -> None:
        """Refuse geometric queries before the first `update`."""
        if not self._updated:
            raise RuntimeError(
                f"Master surface '{self._name}': call update(coords) before searching"
            )

    def _check_points(
        self, points: np.ndarray, tolerances: np.ndarray | float, max_depth: float | None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Validate search input; return points and per-point tolerances as float arrays."""
        points = np.asarray(points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"points must have shape (N, 3), got {points.shape}")
        if not np.all(np.isfinite(points)):
            i = int(np.flatnonzero(~np.all(np.isfinite(points), axis=1))[0])
            raise ValueError(f"points[{i}] is not finite: {points[i].tolist()}")
        tol = np.asarray(tolerances, dtype=float)
        if tol.ndim == 0:
            tol = np.full(points.shape[0], float(tol))
        if tol.shape != (points.shape[0],):
            raise ValueError(
                f"tolerances must be a scalar or have shape ({points.shape[0]},), got {tol.shape}"
            )
        if np.any(~(tol >= 0.0)) or not np.all(np.isfinite(tol)):
            i = int(np.flatnonzero(~((tol >= 0.0) & np.isfinite(tol)))[0])
            raise ValueError(f"tolerances[{i}] = {tol[i]} must be finite and >= 0")
        if max_depth is not None and not (np.isfinite(max_depth) and max_depth >= 0.0):
            raise ValueError(f"max_depth = {max_depth} must be finite and >= 0")
        return points, tol


class _JointSearch:
    """The last search of a surface of several face types, shared by its groups' views."""

    def __init__(self, surface: MasterSurface) -> None:
        self.surface = surface
        self.coords: np.ndarray | None = None  # master node coordinates of the last update
        self.points: np.ndarray | None = None
        self.tolerances: np.ndarray | None = None
        self.faces: np.ndarray | None = None  # (S,) face numbers of the last search
        # the search is repeated for new points or after an update of the surface


class MasterFaceGroup(springs.MeshedMasterSprings):
    """The faces of one type of a :class:`MasterSurface` of several types (docs/method.md §38.8).

    Plays the :class:`~dolfinx_ntf.kernels.master.ContactMaster` role for the pair state of
    that face type: the surface is updated and searched once for all its groups (the walk
    crosses between the kinds, the nodal normals sum both), and each group keeps the slave nodes
    whose face is one of its own, numbered within the group. The groups of one surface search
    the same slave nodes (one slave surface): every node falls in at most one group. The
    stable search (``start_faces`` given) starts each walk at the face the last search found,
    of whichever type (the groups' own previous faces cannot name the others').

    Args:
        surface: The surface of all faces.
        group: Index of this face type in ``surface.face_groups``.
        name: Label for messages.
    """

    collective = False

    def __init__(
        self, surface: MasterSurface, group: int, name: str, *, joint: _JointSearch
    ) -> None:
        self.name = name
        self._surface = surface
        self._group = int(group)
        self._first, self._end = (int(v) for v in surface.group_offsets[group : group + 2])
        self._joint = joint

    @classmethod
    def groups(cls, surface: MasterSurface, name: str) -> list[MasterFaceGroup]:
        """One view per face type of ``surface``, sharing its search."""
        joint = _JointSearch(surface)
        return [
            cls(surface, g, f"{name} ({face_type.name} faces)", joint=joint)
            for g, (face_type, _) in enumerate(surface.face_groups)
        ]

    @property
    def face_type(self) -> FaceType:
        """This group's face type."""
        return self._surface.face_groups[self._group][0]

    def update(self, coords: np.ndarray) -> None:
        """Update the shared surface (once for all groups at the same coordinates)."""
        x = np.asarray(coords, dtype=float)[self._surface.nodes]
        joint = self._joint
        if joint.coords is not None and np.array_equal(joint.coords, x):
            return
        self._surface.update(coords)
        joint.coords = x
        joint.points = None  # the last search was on the surface before this update

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
        """This group's face holding each point (-1: none, or a face of another type)."""
        joint = self._joint
        points = np.asarray(points, dtype=float)
        tol = np.broadcast_to(np.asarray(tolerances, dtype=float), points.shape[:1])
        same = (
            joint.points is not None
            and np.array_equal(joint.points, points)
            and np.array_equal(joint.tolerances, tol)
        )
        if not same:
            start = None
            if start_faces is not None and joint.faces is not None:
                start = joint.faces if joint.faces.size == points.shape[0] else None
            joint.faces = self._surface.locate(
                points,
                tol,
                max_depth=max_depth,
                start_faces=start,
                tie_frame=tie_frame,
                ccx_ties=ccx_ties,
            )
            joint.points, joint.tolerances = points.copy(), tol.copy()
        face = joint.faces
        mine = (face >= self._first) & (face < self._end)
        return np.where(mine, face - self._first, -1)

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The faces of this group sharing a corner with each of ``faces`` (group numbers)."""
        which, patch = self._surface.face_patches(np.asarray(faces, dtype=np.int64) + self._first)
        keep = (patch >= self._first) & (patch < self._end)
        return which[keep], patch[keep] - self._first

    def surface_moments(self) -> tuple[np.ndarray, np.ndarray]:
        """The whole surface's moments (the tie frame of the one search)."""
        return self._surface.surface_moments()


def _check_faces(face_type: FaceType, faces: np.ndarray, name: str) -> np.ndarray:
    """Validate the (F, n) connectivity array and return it as int64."""
    arr = np.asarray(faces)
    if arr.ndim != 2 or arr.shape[1] != face_type.num_nodes:
        raise ValueError(
            f"Master surface '{name}': faces must have shape (F, {face_type.num_nodes}) for "
            f"{face_type.name}, got {arr.shape}"
        )
    if arr.shape[0] == 0:
        raise ValueError(f"Master surface '{name}' has no faces")
    if not np.issubdtype(arr.dtype, np.integer):
        raise ValueError(
            f"Master surface '{name}': faces must be integer node ids, got dtype {arr.dtype}"
        )
    arr = arr.astype(np.int64)
    if np.any(arr < 0):
        f = int(np.flatnonzero(np.any(arr < 0, axis=1))[0])
        raise ValueError(f"Master surface '{name}': face {f} has a negative node id {arr[f]}")
    srt = np.sort(arr, axis=1)
    dup = np.any(srt[:, 1:] == srt[:, :-1], axis=1)
    if face_type.name == "quad4":  # a collapsed wedge's triangle: two neighbouring corners
        adjacent = np.sum(arr == np.roll(arr, -1, axis=1), axis=1) == 1
        dup &= ~(adjacent & (np.sum(srt[:, 1:] == srt[:, :-1], axis=1) == 1))
    if np.any(dup):
        f = int(np.flatnonzero(dup)[0])
        raise ValueError(f"Master surface '{name}': face {f} repeats a node: {arr[f].tolist()}")
    return arr


def _padded_faces(groups: list[tuple[FaceType, np.ndarray]]) -> np.ndarray:
    """(F, n) faces of several types, each row padded with -1 to the widest type."""
    width = max(g.shape[1] for _, g in groups)
    return np.vstack(
        [np.pad(g, ((0, 0), (0, width - g.shape[1])), constant_values=-1) for _, g in groups]
    )


def _group_edges(
    edges: np.ndarray,
    per_item: int | np.ndarray,
    name: str,
    coords: np.ndarray | None,
    item: str,
    items: str,
    real: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Group directed edges by node pair and check they are shared consistently.

    Args:
        edges: (E, 2) directed edges; edge k belongs to item k // per_item.
        per_item: Edges per item (face or triangle), or (E,) the item of each edge (faces of
            several types).
        name: Surface name for messages.
        coords: Optional coordinates for messages.
        item: Singular item name for messages.
        items: Plural item name for messages.
        real: Optional (E,) mask; edges outside it (zero-length edges of faces with a repeated
            corner) are grouped with none.

    Returns:
        Representative edge index per unique edge, unique-edge id per edge, sign (+1 if the
        edge runs like its representative, else -1) per edge, and (P, 2) pairs of edge indices
        shared by two items.
    """
    item_of = (
        (lambda k: k // per_item) if np.ndim(per_item) == 0 else (lambda k: np.asarray(per_item)[k])
    )
    lo, hi = edges.min(axis=1), edges.max(axis=1)
    keys = lo * (int(edges.max()) + 1) + hi
    if real is not None:
        keys = np.where(real, keys, -1 - np.arange(keys.size))
    order = np.argsort(keys, kind="stable")
    sk = keys[order]
    new = np.ones(sk.size, dtype=bool)
    new[1:] = sk[1:] != sk[:-1]
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, sk.size))
    if np.any(counts > 2):
        g = int(np.flatnonzero(counts > 2)[0])
        members = order[starts[g] : starts[g] + counts[g]]
        raise ValueError(
            f"Master surface '{name}': edge {_describe(edges[members[0]], coords)} is shared by "
            f"{counts[g]} {items} ({items} {sorted(item_of(members).tolist())}); a master "
            "edge may border at most two faces (docs/method.md §2.3)"
        )
    group = np.cumsum(new) - 1
    edge_id = np.empty(edges.shape[0], dtype=np.int64)
    edge_id[order] = group
    rep = order[starts]
    pairs = np.stack([order[:-1][~new[1:]], order[1:][~new[1:]]], axis=1)
    same_dir = edges[pairs[:, 0], 0] == edges[pairs[:, 1], 0]
    if np.any(same_dir):
        a, b = pairs[int(np.flatnonzero(same_dir)[0])]
        raise ValueError(
            f"Master surface '{name}': edge {_describe(edges[a], coords)} is traversed in the "
            f"same direction by {item}s {item_of(a)} and {item_of(b)}: neighbouring faces "
            "are inconsistently oriented (the node order must give outward normals)"
        )
    sign = np.where(edges[:, 0] == edges[rep[edge_id], 0], 1, -1)
    return rep, edge_id, sign, pairs


def _describe(edge: np.ndarray, coords: np.ndarray | None) -> str:
    """Edge node ids, with coordinates when available."""
    ids = [int(v) for v in edge]
    if coords is None or coords.ndim != 2 or coords.shape[0] <= max(ids):
        return f"(nodes {ids[0]}, {ids[1]})"
    return f"(nodes {ids[0]} at {coords[ids[0]].tolist()}, {ids[1]} at {coords[ids[1]].tolist()})"
