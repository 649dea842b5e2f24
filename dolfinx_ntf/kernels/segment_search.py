"""The master curve of a 2D mesh: nodal normals, bounding lines and the edge walk.

The 2D counterpart of ``search.py`` (docs/method.md §2.3, §3.2). Every corner node of the master
curve has an averaged unit normal; the line through the node along that normal bounds the two
edges meeting there, so the regions of neighbouring edges tile the plane near the curve without
gaps. A slave node is located by walking from the edge with the nearest midpoint across violated
bounding lines, as the triangle walk does in 3D. Midpoints equally near (to ``TIE_DIGITS`` digits
of the curve's size) are taken in ``(x, y)`` order, so the start, and the edge of a node exactly
above a master node, depend neither on the order of the edges (which follows the partition) nor
on k-d tree internals.

Pure numpy/scipy; nodes are integer ids indexing rows of a coordinate array (2 or 3 columns, a
third, z = 0, is ignored).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from dolfinx_ntf.kernels.edges import EdgeType
from dolfinx_ntf.kernels.friction import FrictionInput
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.search import TIE_CANDIDATES, TIE_DIGITS
from dolfinx_ntf.kernels.segment_springs import evaluate_segment_springs
from dolfinx_ntf.kernels.springs import SpringEvaluation
from dolfinx_ntf.kernels.tie_frame import TieFrame

__all__ = ["MasterCurve"]

MAX_WALK_STEPS = 100
"""A walk taking more steps than this finds no edge."""


class MasterCurve:
    """Master edges of a 2D mesh playing the :class:`~dolfinx_ntf.kernels.master.ContactMaster`.

    Args:
        edge_type: Type of all edges.
        faces: (F, n) node ids of the edges, corners oriented with the body on the left.
        name: Surface name for messages.
        coords: Optional (num_nodes, 2 or 3) coordinates: ``update(coords)`` at construction.
        fallback_factor: The area of a spring whose slave node has none (a faceless node) is
            ``|q_ξ|`` times this (evaluate_segment_springs).
        fallback_ring: That area is a ring area: also times ``2 pi r`` of the projection point.

    Raises:
        ValueError: If a corner node joins more than two edges or two edges meeting at a node are
            oriented inconsistently.
    """

    collective = False

    def __init__(
        self,
        edge_type: EdgeType,
        faces: np.ndarray,
        *,
        name: str = "master",
        coords: np.ndarray | None = None,
        fallback_factor: float = 1.0,
        fallback_ring: bool = False,
    ) -> None:
        self.fallback_factor = float(fallback_factor)
        self.fallback_ring = bool(fallback_ring)
        faces = np.asarray(faces, dtype=np.int64)
        if faces.ndim != 2 or faces.shape[1] != edge_type.num_nodes or faces.shape[0] == 0:
            raise ValueError(
                f"Master surface '{name}': faces must have shape (F, {edge_type.num_nodes}) "
                f"with F > 0, got {faces.shape}"
            )
        self.name = name
        self.face_type = edge_type
        self.faces = faces
        corners = faces[:, :2]
        self._nodes, local = np.unique(corners, return_inverse=True)
        self._local = local.reshape(-1, 2)
        num = self._nodes.size
        starts = np.bincount(self._local[:, 0], minlength=num)
        ends = np.bincount(self._local[:, 1], minlength=num)
        bad = np.flatnonzero((starts > 1) | (ends > 1))
        if bad.size:
            raise ValueError(
                f"Master surface '{name}': node {int(self._nodes[bad[0]])} starts or ends more "
                "than one edge: the master curve branches or its edges are inconsistently "
                "oriented"
            )
        edge_starting = np.full(num, -1, dtype=np.int64)
        edge_ending = np.full(num, -1, dtype=np.int64)
        edge_starting[self._local[:, 0]] = np.arange(faces.shape[0])
        edge_ending[self._local[:, 1]] = np.arange(faces.shape[0])
        #: (F, 2) edge before (across corner 0) and after (across corner 1), -1: none.
        self.neighbours = np.stack(
            [edge_ending[self._local[:, 0]], edge_starting[self._local[:, 1]]], axis=1
        )
        self._updated = False
        if coords is not None:
            self.update(coords)

    @property
    def num_faces(self) -> int:
        """Number of master edges."""
        return int(self.faces.shape[0])

    def update(self, coords: np.ndarray) -> None:
        """Nodal normals, bounding lines and the midpoint tree at the current coordinates."""
        x = np.asarray(coords, dtype=float)[:, :2]
        ends = np.array([[-1.0], [1.0]])
        dphi = self.face_type.shape_derivatives(ends)  # (2, n)
        tangents = np.einsum("ej,fjc->fec", dphi, x[self.faces])  # (F, 2 ends, 2)
        norm = np.linalg.norm(tangents, axis=2)
        if np.any(~(norm > 0.0)):
            f = int(np.flatnonzero(~np.all(norm > 0.0, axis=1))[0])
            raise ValueError(f"Master surface '{self.name}': edge {f} is degenerate")
        unit = np.stack([tangents[..., 1], -tangents[..., 0]], axis=2) / norm[..., None]
        acc = np.zeros((self._nodes.size, 2))
        np.add.at(acc, self._local.ravel(), unit.reshape(-1, 2))
        anorm = np.linalg.norm(acc, axis=1)
        if np.any(~(anorm > 1e-12)):
            k = int(np.flatnonzero(~(anorm > 1e-12))[0])
            raise ValueError(
                f"Master surface '{self.name}': the edge normals at node {self._nodes[k]} cancel"
            )
        nodal = acc / anorm[:, None]
        #: Unit direction of each corner's bounding line's normal, along the traversal.
        self._along = np.stack([-nodal[:, 1], nodal[:, 0]], axis=1)
        self._corner_x = x[self._nodes]
        a, b = x[self.faces[:, 0]], x[self.faces[:, 1]]
        chord = b - a
        self._chord_normal = (
            np.stack([chord[:, 1], -chord[:, 0]], axis=1) / np.linalg.norm(chord, axis=1)[:, None]
        )
        midpoints = 0.5 * (a + b)
        self._tree = cKDTree(midpoints)
        corners = x[self._nodes]
        origin = corners.min(axis=0)
        scale = float(np.ptp(corners, axis=0).max()) or 1.0
        self._tie_width = 10.0**-TIE_DIGITS * scale
        rounded = np.round((midpoints - origin) / scale, TIE_DIGITS)
        self._midpoint_rank = np.empty(midpoints.shape[0], dtype=np.int64)
        self._midpoint_rank[np.lexsort(rounded.T[::-1])] = np.arange(midpoints.shape[0])
        self._updated = True

    def _nearest_midpoints(self, points: np.ndarray) -> np.ndarray:
        """The edge with the nearest midpoint to each point, ties taken in ``(x, y)`` order."""
        k = min(TIE_CANDIDATES, self.num_faces)
        distance, nearest = self._tree.query(points, k=k)
        distance, nearest = distance.reshape(-1, k), nearest.reshape(-1, k)
        tied = distance <= distance[:, :1] + self._tie_width
        rank = np.where(tied, self._midpoint_rank[nearest], np.iinfo(np.int64).max)
        return nearest[np.arange(nearest.shape[0]), np.argmin(rank, axis=1)].astype(np.int64)

    def locate(
        self,
        points: np.ndarray,
        tolerances: np.ndarray | float,
        *,
        max_depth: float | None = None,
        start_faces: np.ndarray | None = None,
        tie_frame: TieFrame | None = None,
        ccx_ties: bool = False,
        max_steps: int = MAX_WALK_STEPS,
    ) -> np.ndarray:
        """Edge holding each point (-1: none), by the walk across bounding lines."""
        if not self._updated:
            raise RuntimeError(f"Master surface '{self.name}': call update(coords) first")
        points = np.asarray(points, dtype=float)[:, :2]
        num = points.shape[0]
        tol = np.broadcast_to(np.asarray(tolerances, dtype=float), (num,))
        result = np.full(num, -1, dtype=np.int64)
        if num == 0:
            return result
        current = self._nearest_midpoints(points)
        if start_faces is not None:
            start = np.asarray(start_faces, dtype=np.int64)
            current = np.where(start >= 0, start, current)
        previous = np.full(num, -1, dtype=np.int64)
        idx = np.arange(num)
        for _ in range(max_steps + 1):
            corner = self._local[current]  # (m, 2)
            p = points[idx]
            before = (
                np.einsum("nc,nc->n", p - self._corner_x[corner[:, 0]], self._along[corner[:, 0]])
                < -tol[idx]
            )
            after = (
                np.einsum("nc,nc->n", p - self._corner_x[corner[:, 1]], self._along[corner[:, 1]])
                > tol[idx]
            )
            moving = before | after
            result[idx[~moving]] = current[~moving]
            nb = np.where(before, self.neighbours[current, 0], self.neighbours[current, 1])
            back = moving & (nb == previous) & (nb >= 0)  # between two edges: keep this one
            result[idx[back]] = current[back]
            moving &= (nb >= 0) & ~back
            idx, previous, current = idx[moving], current[moving], nb[moving]
            if idx.size == 0:
                break
        if max_depth is not None:
            found = np.flatnonzero(result >= 0)
            f = result[found]
            depth = -np.einsum(
                "nc,nc->n", self._chord_normal[f], points[found] - self._corner_x[self._local[f, 0]]
            )
            result[found[depth > max_depth]] = -1
        return result

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(which, patch)``: each edge and its neighbours, ``patch[k]`` by ``faces[which[k]]``."""
        faces = np.asarray(faces, dtype=np.int64)
        around = np.stack([self.neighbours[faces, 0], faces, self.neighbours[faces, 1]], axis=1)
        which = np.repeat(np.arange(faces.size), 3)
        keep = around.ravel() >= 0
        return which[keep], around.ravel()[keep]

    def surface_moments(self) -> None:
        """No tie frame in 2D: ties of the nearest midpoint are taken in ``(x, y)`` order."""
        return None

    def evaluate_springs(
        self,
        face_type: EdgeType,
        master_coords: np.ndarray,
        slave_coords: np.ndarray,
        areas: np.ndarray,
        law: PressureOverclosureLaw,
        *,
        gap_shift: float | np.ndarray = 0.0,
        xi0: np.ndarray | None = None,
        tangent: bool = True,
        symmetric: bool = False,
        friction: FrictionInput | None = None,
        interior_projection: bool = False,
        damping: object | None = None,
    ) -> SpringEvaluation:
        """:func:`~dolfinx_ntf.kernels.segment_springs.evaluate_segment_springs` on these edges.

        Contact ``damping`` is refused: not supported on 2D meshes yet (docs/method.md §29).
        """
        if damping is not None:
            raise NotImplementedError(
                "contact damping is not supported on 2D meshes yet (docs/method.md §29)"
            )
        return evaluate_segment_springs(
            face_type,
            master_coords,
            slave_coords,
            areas,
            law,
            gap_shift=gap_shift,
            xi0=xi0,
            tangent=tangent,
            symmetric=symmetric,
            interior_projection=interior_projection,
            friction=friction,
            fallback_factor=self.fallback_factor,
            fallback_ring=self.fallback_ring,
        )
