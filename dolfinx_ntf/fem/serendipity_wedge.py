"""The 15-node serendipity wedge (CalculiX C3D15) as a constrained P2 prism space.

See docs/method.md §34. ccx's C3D15 space lies inside the 18-node Lagrange prism (the quadratic
triangle times the quadratic interval): it is the P2 prism functions whose values at the centres
of the three quadrilateral faces are fixed by the 8 other nodes of the face,

    u(face centre) = -1/4 sum(4 face corners) + 1/2 sum(4 face midside nodes),

the value the quad8 shape functions take there (as C3D20's faces, ``fem/serendipity.py``). Local
nodes of basix's degree-2 prism: 0..5 the vertices (triangle 0-1-2 below 3-4-5), 6..14 the
edges (0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5), 15..17 the centres of the quadrilateral
faces (0-1-3-4, 0-2-3-5, 1-2-4-5). Prism cells with P2 spaces run on dolfinx 0.11 only
(docs/method.md §32.5).
"""

from __future__ import annotations

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import LinearConstraintBlock

__all__ = [
    "QUADRATIC_PRISMS_MIN_DOLFINX",
    "add_wedge_centres",
    "require_quadratic_prisms",
    "wedge15_metadata",
    "wedge15_rule",
    "wedge15_space",
    "wedge_forces_on_nodes",
    "wedge_serendipity_constraints",
]

#: The first dolfinx release that assembles degree-2 spaces on prisms (docs/method.md §32.5).
QUADRATIC_PRISMS_MIN_DOLFINX = (0, 11)


def require_quadratic_prisms(what: str, sections: str) -> None:
    """Refuse ``what`` (the subject of the message) on a dolfinx that cannot run P2 on prisms.

    Raises:
        NotImplementedError: dolfinx older than 0.11: its reason, and the ``sections`` of
            docs/method.md to read.
    """
    if compat.DOLFINX_VERSION >= QUADRATIC_PRISMS_MIN_DOLFINX:
        return
    version = ".".join(map(str, compat.DOLFINX_VERSION))
    why = (
        "its FFCx refuses forms on prisms"
        if compat.DOLFINX_VERSION < (0, 7)
        else "degree-2 spaces on prisms abort the process while assembling"
    )
    raise NotImplementedError(
        f"{what} need dolfinx 0.11 or later (an 18-node prism mesh with a degree-2 space); "
        f"dolfinx {version} cannot: {why} (docs/method.md {sections})"
    )


# basix reference prism: edges and quadrilateral faces by their vertices.
_EDGES = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 4), (2, 5), (3, 4), (3, 5), (4, 5)]
_QUADS = [(0, 1, 3, 4), (0, 2, 3, 5), (1, 2, 4, 5)]
#: Weights of a face centre's value: its 4 corners, then its 4 midside nodes.
_FACE_WEIGHTS = np.array([-0.25] * 4 + [0.5] * 4)


def _face_rows() -> np.ndarray:
    """``(3, 9)`` local nodes of each quadrilateral face: its centre, 4 corners, 4 midsides."""
    rows = []
    for f, face in enumerate(_QUADS):
        edges = [6 + e for e, (a, b) in enumerate(_EDGES) if a in face and b in face]
        rows.append([15 + f, *face, *edges])
    return np.array(rows, dtype=np.int64)


_FACE_ROWS = _face_rows()


def add_wedge_centres(cells: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """18-node cells from 15-node ones (dolfinx order): the quad face centres appended to ``x``.

    ``cells`` are ``(C, 15)`` rows into ``x`` in dolfinx's order of an 18-node prism (vertices,
    then edges). Each centre is placed by the quad8 map of its face's 8 nodes, so the geometry is
    exactly C3D15's isoparametric map; a face shared by two cells gets one node (keyed by its
    sorted corners). Their rows come after those of ``x``.

    Args:
        cells: ``(C, 15)`` (or wider: the first 15 columns are used) rows into ``x``.
        x: ``(N, gdim)`` node coordinates.

    Returns:
        ``(cells, x)``: ``(C, 18)`` rows and the coordinates with the centres appended.
    """
    faces = cells[:, _FACE_ROWS[:, 1:]]  # (C, 3, 8)
    face_x = np.einsum("k,cfkd->cfd", _FACE_WEIGHTS, x[faces])
    keys = np.sort(faces[:, :, :4], axis=2).reshape(-1, 4)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    face_node = x.shape[0] + inverse.ravel().reshape(cells.shape[0], 3)
    x = np.vstack([x, face_x.reshape(-1, x.shape[1])[first]])
    return np.hstack([cells[:, :15], face_node]), x


def wedge_serendipity_constraints(V: dolfinx.fem.FunctionSpace) -> list[LinearConstraintBlock]:
    """Constraints that turn a degree-2 Lagrange space on prisms into C3D15's space.

    Args:
        V: Vector (displacement) or scalar (temperature, docs/method.md §39) Lagrange space of
            degree 2 on a prism mesh (this process's cells, ghosts included; a face between two
            processes' cells is given on both).

    Returns:
        One block of 9-term rows (each quadrilateral face once, each component; the centre
        first, the dependent dof). Dirichlet conditions must leave the centres free.
    """
    if V.mesh.topology.cell_type != dolfinx.mesh.CellType.prism:
        raise ValueError("wedge_serendipity_constraints: a prism mesh is needed")
    bs = V.dofmap.index_map_bs
    if compat.space_degree(V) != 2 or bs not in (1, 3):
        raise ValueError(
            "wedge_serendipity_constraints: a degree-2 vector or scalar Lagrange space is needed"
        )
    dofs = compat.cell_dofs(V).astype(np.int64)
    if dofs.shape[1] != 18:
        raise ValueError(
            f"wedge_serendipity_constraints: 18 dofs per cell expected, got {dofs.shape[1]}"
        )
    nodes = dofs[:, _FACE_ROWS].reshape(-1, 9)
    _, first = np.unique(nodes[:, 0], return_index=True)  # a shared face once
    nodes = nodes[np.sort(first)]
    return [
        LinearConstraintBlock(
            np.repeat(nodes, bs, axis=0),
            np.tile(np.arange(bs), nodes.shape[0])[:, None],
            np.concatenate([[1.0], -_FACE_WEIGHTS]),
            name="C3D15 face centres",
            block_size=bs,
        )
    ]


def wedge_forces_on_nodes(values: np.ndarray, space: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Element nodal forces of a broken P2 prism vector as C3D15's: ``(cells, 15, 3)`` flattened.

    Each face centre's force moves to the 8 nodes it depends on (virtual work), so that ccx's
    average element force (docs/method.md §7.1) is taken over the 15 nodes of each element. On
    several processes: the owned cells.

    Args:
        values: The broken (per-cell) vector's values.
        space: Its space (18 dofs of 3 components per cell).
    """
    num_owned = space.mesh.topology.index_map(space.mesh.topology.dim).size_local
    dofs = compat.cell_dofs(space)[:num_owned]
    forces = np.asarray(values).reshape(-1, 3)[dofs]  # (cells, 18, 3)
    return (forces[:, :15] + np.einsum("kn,ckd->cnd", _CENTRE_WEIGHTS, forces[:, 15:])).ravel()


def _centre_weights() -> np.ndarray:
    """``(3, 15)``: value of face centre ``k`` from the 15 local nodes."""
    weights = np.zeros((3, 15))
    for k, row in enumerate(_FACE_ROWS):
        weights[k, row[1:]] = _FACE_WEIGHTS
    return weights


_CENTRE_WEIGHTS = _centre_weights()


_G3 = (-np.sqrt(0.6), 0.0, np.sqrt(0.6))
_TRI_POINTS = ((1 / 6, 1 / 6), (2 / 3, 1 / 6), (1 / 6, 2 / 3))


def wedge15_rule() -> tuple[np.ndarray, np.ndarray]:
    """ccx's 9 points of C3D15 on basix's reference prism and their weights (sum 1/2).

    The 3-point triangle rule (weights 1/6) times 3 Gauss points along the axis (5/18, 8/18,
    5/18 on ``[0, 1]``), the triangle points fastest (docs/method.md §34.2). It integrates the
    stiffness less exactly than basix's degree-5 rule, as ccx does.
    """
    points = np.array([[a, b, (z + 1) / 2] for z in _G3 for a, b in _TRI_POINTS])
    weights = np.repeat([5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0], 3) / 6.0
    return points, weights


def wedge15_metadata() -> dict:
    """UFL integral metadata of :func:`wedge15_rule` (FFCx's custom rule), e.g. for ``ufl.dx``."""
    points, weights = wedge15_rule()
    return {
        "quadrature_rule": "custom",
        "quadrature_degree": 2,
        "quadrature_points": tuple(map(tuple, points.tolist())),
        "quadrature_weights": tuple(weights.tolist()),
    }


def wedge15_space(
    mesh: dolfinx.mesh.Mesh,
) -> tuple[dolfinx.fem.FunctionSpace, list[LinearConstraintBlock]]:
    """C3D15's displacement space on an 18-node prism mesh: vector P2 and its face constraints.

    Args:
        mesh: A prism mesh of degree-2 geometry (e.g. from ``meshes.gmsh_io`` on dolfinx 0.11).

    Returns:
        ``(V, constraints)``: the vector degree-2 Lagrange space and
        :func:`wedge_serendipity_constraints` of it (pass them to ``ContactProblem`` or
        ``ConstraintElimination``; Dirichlet conditions must leave the face centres free).

    Raises:
        NotImplementedError: dolfinx older than 0.11 (no degree-2 spaces on prisms).
        ValueError: the mesh is not of prisms.
    """
    if compat.DOLFINX_VERSION < (0, 11):
        raise NotImplementedError(
            "wedge15_space: degree-2 spaces on prisms need dolfinx 0.11 or later "
            "(docs/method.md §32.5)"
        )
    if mesh.topology.cell_type != dolfinx.mesh.CellType.prism:
        raise ValueError("wedge15_space: a prism mesh is needed")
    V = compat.vector_space(mesh, "Lagrange", 2)
    return V, wedge_serendipity_constraints(V)
