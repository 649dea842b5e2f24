"""Master/slave edge types of 2D meshes: shape functions, spring-area weights, lengths.

Pure numpy. An edge is the boundary facet of a 2D cell. Its node order is corners first (the
boundary of the body traversed counter-clockwise, the body on the left), then the midside node,
so that the outward normal is the tangent ``q_ξ`` turned clockwise, ``m = (q_ξ,y, -q_ξ,x)``:

- line2: φ = ((1 - ξ)/2, (1 + ξ)/2) on ``[-1, 1]``;
- line3: φ = (ξ(ξ - 1)/2, ξ(ξ + 1)/2, 1 - ξ²), the midside node at ξ = 0.

Spring-area weights are the integrals of the shape functions over the edge (the tributary
length): 1/2 each for line2, Simpson's 1/6, 1/6, 2/3 for line3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "EDGE_TYPES",
    "LINE2",
    "LINE3",
    "EdgeType",
    "edge_lengths",
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
    order = np.argsort(slave_nodes)
    position = np.minimum(np.searchsorted(slave_nodes[order], edges), max(slave_nodes.size - 1, 0))
    hit = slave_nodes[order][position] == edges if slave_nodes.size else np.zeros(edges.shape, bool)
    index = order[position[hit]]
    return np.bincount(index, weights=shares[hit], minlength=slave_nodes.size).astype(float)
