"""Master/slave edge types of 2D meshes: shape functions, spring-area weights, lengths.

Pure numpy. An edge is the boundary facet of a 2D cell. Its node order is corners first (the
boundary of the body traversed counter-clockwise, the body on the left), then the midside node,
so that the outward normal is the tangent ``q_ξ`` turned clockwise, ``m = (q_ξ,y, -q_ξ,x)``:

- line2: φ = ((1 - ξ)/2, (1 + ξ)/2) on ``[-1, 1]``;
- line3: φ = (ξ(ξ - 1)/2, ξ(ξ + 1)/2, 1 - ξ²), the midside node at ξ = 0.

Spring-area weights are the integrals of the shape functions over the edge (the tributary
length): 1/2 each for line2, Simpson's 1/6, 1/6, 2/3 for line3. Axisymmetric spring areas weight
the same integrals by the circumference 2 pi r (docs/method.md §17.2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "CCX_EDGE_SHARES",
    "EDGE_TYPES",
    "LINE2",
    "LINE3",
    "EdgeType",
    "axisymmetric_edge_spring_areas",
    "ccx_edge_spring_areas",
    "edge_lengths",
    "edge_spring_area_gradients",
    "edge_spring_areas",
    "edge_type_from_num_nodes",
]


@dataclass(frozen=True, eq=False)
class EdgeType:
    """An edge type (1D parametric domain ``[-1, 1]``).

    Attributes:
        name: ``"line2"`` or ``"line3"``.
        num_nodes: Number of edge nodes n.
        area_weights: (n,) share of the edge length each node takes (sums to 1).
    """

    name: str
    num_nodes: int
    area_weights: np.ndarray

    num_corners = 2
    is_triangle = False
    is_edge = True

    @property
    def center(self) -> np.ndarray:
        """Parametric centre of the edge, shape (1,)."""
        return np.zeros(1)

    @property
    def node_parameters(self) -> np.ndarray:
        """(n, 1) parametric coordinates of the nodes."""
        return np.array([[-1.0], [1.0], [0.0]])[: self.num_nodes]

    def shape_functions(self, xi: npt.ArrayLike) -> np.ndarray:
        """φ_j at ``xi`` (..., 1) -> (..., n)."""
        x = _parameter(xi)
        if self.num_nodes == 2:
            return np.stack([0.5 * (1.0 - x), 0.5 * (1.0 + x)], axis=-1)
        return np.stack([0.5 * x * (x - 1.0), 0.5 * x * (x + 1.0), 1.0 - x * x], axis=-1)

    def shape_derivatives(self, xi: npt.ArrayLike) -> np.ndarray:
        """dφ_j/dξ at ``xi`` (..., 1) -> (..., n)."""
        x = _parameter(xi)
        if self.num_nodes == 2:
            half = np.full_like(x, 0.5)
            return np.stack([-half, half], axis=-1)
        return np.stack([x - 0.5, x + 0.5, -2.0 * x], axis=-1)

    def shape_second_derivatives(self, xi: npt.ArrayLike) -> np.ndarray:
        """d²φ_j/dξ² at ``xi`` (..., 1) -> (..., n)."""
        x = _parameter(xi)
        values = [0.0, 0.0] if self.num_nodes == 2 else [1.0, 1.0, -2.0]
        return np.broadcast_to(np.array(values), (*x.shape, self.num_nodes)).copy()


def _parameter(xi: npt.ArrayLike) -> np.ndarray:
    """ξ of parametric coordinates (..., 1) as an array (...)."""
    arr = np.asarray(xi, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 1:
        raise ValueError(f"edge parameters xi must have shape (..., 1), got {arr.shape}")
    return arr[..., 0]


LINE2 = EdgeType("line2", 2, np.array([0.5, 0.5]))
LINE3 = EdgeType("line3", 3, np.array([1.0, 1.0, 4.0]) / 6.0)
EDGE_TYPES = {t.name: t for t in (LINE2, LINE3)}


def edge_type_from_num_nodes(n: int) -> EdgeType:
    """The edge type with ``n`` nodes (2 or 3)."""
    for edge_type in EDGE_TYPES.values():
        if edge_type.num_nodes == n:
            return edge_type
    raise ValueError(f"no edge type with {n} nodes (2D meshes: 2 or 3 nodes per boundary edge)")


# Gauss-Legendre rule exact for the length of a straight quadratic edge and close for curved ones.
_GAUSS_POINTS, _GAUSS_WEIGHTS = np.polynomial.legendre.leggauss(4)


def edge_lengths(edge_type: EdgeType, edge_coords: npt.ArrayLike) -> np.ndarray:
    """Lengths of edges with node coordinates (F, n, 2 or 3) -> (F,)."""
    coords = np.asarray(edge_coords, dtype=float)[..., :2]
    if coords.ndim != 3 or coords.shape[1] != edge_type.num_nodes:
        raise ValueError(
            f"edge_coords must have shape (F, {edge_type.num_nodes}, 2 or 3), got {coords.shape}"
        )
    if edge_type.num_nodes == 2:
        return np.linalg.norm(coords[:, 1] - coords[:, 0], axis=1)
    dphi = edge_type.shape_derivatives(_GAUSS_POINTS[:, None])  # (q, n)
    tangents = np.einsum("qj,fjc->fqc", dphi, coords)
    return np.linalg.norm(tangents, axis=2) @ _GAUSS_WEIGHTS


def edge_spring_areas(
    edge_type: EdgeType, edges: np.ndarray, coords: np.ndarray, slave_nodes: np.ndarray
) -> np.ndarray:
    """Tributary lengths ``Σ_{e∋p} w_p |e|`` of the slave nodes (per unit thickness) -> (S,).

    Args:
        edge_type: Type of every slave edge.
        edges: (F, n) node ids of the slave edges (rows index ``coords``).
        coords: (num_nodes, 2 or 3) node coordinates (current configuration).
        slave_nodes: (S,) unique node ids; a slave node on no edge gets 0.
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, edge_type.num_nodes)
    slave_nodes = np.asarray(slave_nodes, dtype=np.int64)
    shares = edge_lengths(edge_type, np.asarray(coords)[edges])[:, None] * edge_type.area_weights
    return _sum_to_nodes(edges, shares, slave_nodes)


# Radii below zero by less than this fraction of the edge's length count as on the axis.
_AXIS_TOL = 1e-9


def axisymmetric_edge_spring_areas(
    edge_type: EdgeType, edges: np.ndarray, coords: np.ndarray, slave_nodes: np.ndarray
) -> np.ndarray:
    """Ring areas ``A_p = 2 pi Σ_{e∋p} ∫_e r φ_p ds`` of the slave nodes (axisymmetric) -> (S,).

    ``r = x[0]`` is the distance from the axis. The areas are the consistent nodal shares of a
    uniform pressure on the surface of revolution (they sum to its area ``2 pi ∫ r ds``), so a
    uniform pressure is transmitted exactly; in the interior of a uniform line2 mesh
    ``A_p = 2 pi r_p L_p`` with the tributary length ``L_p``. A node on the axis keeps the share
    of its line2 edges (``2 pi L²/6`` for an edge of length ``L``); a line3 corner on the axis
    gets exactly 0 (its consistent share), never a negative area or NaN.

    Args:
        edge_type: Type of every slave edge.
        edges: (F, n) node ids of the slave edges (rows index ``coords``).
        coords: (num_nodes, 2 or 3) node coordinates (current configuration), ``x[0] = r``.
        slave_nodes: (S,) unique node ids; a slave node on no edge gets 0.

    Raises:
        ValueError: A slave edge has a node at ``r < 0`` (off the meridian half-plane).
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, edge_type.num_nodes)
    slave_nodes = np.asarray(slave_nodes, dtype=np.int64)
    xy = np.asarray(coords, dtype=float)[edges][..., :2]  # (F, n, 2)
    lengths = edge_lengths(edge_type, xy)
    outside = np.flatnonzero(np.any(xy[..., 0] < -_AXIS_TOL * lengths[:, None], axis=1))
    if outside.size:
        node = edges[outside[0]][np.argmin(xy[outside[0], :, 0])]
        raise ValueError(
            f"axisymmetric spring areas need r = x[0] >= 0; {outside.size} slave edge(s) reach "
            f"r < 0 (node {node} at r = {xy[outside[0], :, 0].min():.6g})"
        )
    points = _GAUSS_POINTS[:, None]
    phi = edge_type.shape_functions(points)  # (q, n)
    jacobian = np.linalg.norm(
        np.einsum("qj,fjc->fqc", edge_type.shape_derivatives(points), xy), axis=2
    )
    radius = np.maximum(np.einsum("qj,fj->fq", phi, xy[..., 0]), 0.0)  # (F, q)
    shares = 2.0 * np.pi * np.einsum("fq,qj->fj", radius * jacobian * _GAUSS_WEIGHTS, phi)
    # A line3 corner on the axis has the share 0 exactly (round-off: ±1e-19); none is negative.
    shares[shares <= _AXIS_TOL * shares.sum(axis=1, keepdims=True)] = 0.0
    return _sum_to_nodes(edges, shares, slave_nodes)


#: CalculiX 2.20's shares of a 2D edge's area per node (corners, then the midside node): ccx expands
#: the edge into a quad4 face (a quarter to each of its corners, two per 2D node) or, for a line3
#: edge, a quad8 face (1/100 to each corner, 24/100 to each midside node: a 2D corner node has two
#: corners and its mid-plane midside node, the 2D midside node two midside nodes), spec §2.2.
CCX_EDGE_SHARES = {2: np.array([0.5, 0.5]), 3: np.array([0.26, 0.26, 0.48])}


def ccx_edge_spring_areas(
    edge_type: EdgeType,
    edges: np.ndarray,
    coords: np.ndarray,
    slave_nodes: np.ndarray,
    *,
    thickness: float = 1.0,
    axisymmetric: bool = False,
) -> np.ndarray:
    """CalculiX's spring areas of 2D slave nodes: its expanded faces' fixed shares -> (S,).

    Each edge's area (its length times ``thickness``, or with ``axisymmetric`` its ring area
    ``2 pi ∫ r ds``) is shared among its nodes by ``CCX_EDGE_SHARES``: 1/2, 1/2 on a line2 edge
    (the plane tributary rule; on a ring each node gets half the edge's ring area, the share of its
    mean radius, where the consistent shares weight each node by its own radius), 26/100, 26/100,
    48/100 on a line3 edge (Simpson's 1/6, 1/6, 2/3 are the consistent ones). docs/method.md §23.3.

    Args:
        edge_type: Type of every slave edge.
        edges: (F, n) node ids of the slave edges (rows index ``coords``).
        coords: (num_nodes, 2 or 3) node coordinates (current configuration).
        slave_nodes: (S,) unique node ids; a slave node on no edge gets 0.
        thickness: Out-of-plane thickness of plane models (1 with ``axisymmetric``).
        axisymmetric: Ring areas (``x[0] = r``).
    """
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, edge_type.num_nodes)
    slave_nodes = np.asarray(slave_nodes, dtype=np.int64)
    each = np.arange(edges.size, dtype=np.int64).reshape(edges.shape)  # every edge node its own
    if axisymmetric:
        flat = np.asarray(coords, dtype=float)[edges.ravel()]
        totals = axisymmetric_edge_spring_areas(edge_type, each, flat, each.ravel())
        totals = totals.reshape(edges.shape).sum(axis=1)
    else:
        xy = np.asarray(coords, dtype=float)[edges][..., :2]
        totals = thickness * edge_lengths(edge_type, xy)
    shares = totals[:, None] * CCX_EDGE_SHARES[edge_type.num_nodes][None, :]
    return _sum_to_nodes(edges, shares, slave_nodes)


def edge_spring_area_gradients(
    edge_type: EdgeType,
    edges: np.ndarray,
    coords: np.ndarray,
    slave_nodes: np.ndarray,
    *,
    thickness: float = 1.0,
    axisymmetric: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Derivatives ``∂A_p/∂x_q`` of 2D spring areas as COO triplets (duplicates summed).

    The areas are ``thickness`` times :func:`edge_spring_areas`, or
    :func:`axisymmetric_edge_spring_areas` with ``axisymmetric`` (its shares set to 0 on the axis
    are differentiated as computed, unclamped); ``linearize_area`` (docs/method.md §6.3, §17.2).

    Args:
        edge_type: Type of every slave edge.
        edges: (F, n) node ids of the slave edges.
        coords: (num_nodes, 2 or 3) current node coordinates.
        slave_nodes: (S,) unique node ids.
        thickness: Out-of-plane thickness of plane models (1 with ``axisymmetric``).
        axisymmetric: Ring areas ``2 pi ∫ r φ_p ds``.

    Returns:
        ``(slave_index (K,), node (K,), gradient (K, 2))``: ``slave_index`` indexes
        ``slave_nodes``, ``node`` is a node id; pairs are unique and sorted by
        ``(slave_index, node)``.
    """
    n = edge_type.num_nodes
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, n)
    slave_nodes = np.asarray(slave_nodes, dtype=np.int64)
    xy = np.asarray(coords, dtype=float)[edges][..., :2]  # (F, n, 2)
    points = _GAUSS_POINTS[:, None]
    phi = edge_type.shape_functions(points)  # (q, n)
    dphi = edge_type.shape_derivatives(points)
    tangent = np.einsum("qj,fjc->fqc", dphi, xy)  # (F, q, 2)
    jacobian = np.linalg.norm(tangent, axis=2)  # (F, q)
    unit = tangent / jacobian[..., None]
    # ∂J_q/∂x_kc = t̂_c φ'_k(q): (F, q, k, c)
    djac = unit[:, :, None, :] * dphi[None, :, :, None]
    if axisymmetric:  # share_p = 2 pi Σ_q w_q φ_p r_q J_q
        radius = np.einsum("qj,fj->fq", phi, xy[..., 0])
        dproduct = radius[:, :, None, None] * djac
        dproduct[..., 0] += phi[None, :, :] * jacobian[:, :, None]
        grads = 2.0 * np.pi * np.einsum("q,qp,fqkc->fpkc", _GAUSS_WEIGHTS, phi, dproduct)
    else:  # share_p = t w_p Σ_q w_q J_q
        dlength = np.einsum("q,fqkc->fkc", _GAUSS_WEIGHTS, djac)
        grads = thickness * edge_type.area_weights[None, :, None, None] * dlength[:, None]
    order = np.argsort(slave_nodes)
    position = np.minimum(np.searchsorted(slave_nodes[order], edges), max(slave_nodes.size - 1, 0))
    hit = slave_nodes[order][position] == edges if slave_nodes.size else np.zeros(edges.shape, bool)
    face_of, local_of = np.nonzero(hit)
    rows = np.repeat(order[position[face_of, local_of]], n)
    cols = edges[face_of].reshape(-1)
    values = grads[face_of, local_of].reshape(-1, 2)
    num_nodes = int(max(edges.max(initial=-1), slave_nodes.max(initial=-1))) + 1
    keys = rows * num_nodes + cols
    unique_keys, inverse = np.unique(keys, return_inverse=True)
    summed = np.stack(
        [np.bincount(inverse, weights=values[:, c], minlength=unique_keys.size) for c in range(2)],
        axis=1,
    )
    return unique_keys // num_nodes, unique_keys % num_nodes, summed


def _sum_to_nodes(edges: np.ndarray, shares: np.ndarray, slave_nodes: np.ndarray) -> np.ndarray:
    """Sum the (F, n) per-edge node shares onto the (S,) slave nodes (0 where none)."""
    order = np.argsort(slave_nodes)
    position = np.minimum(np.searchsorted(slave_nodes[order], edges), max(slave_nodes.size - 1, 0))
    hit = slave_nodes[order][position] == edges if slave_nodes.size else np.zeros(edges.shape, bool)
    index = order[position[hit]]
    return np.bincount(index, weights=shares[hit], minlength=slave_nodes.size).astype(float)
