"""The 8-node serendipity quadrilateral (CalculiX CPE8, CPS8, CAX8) as a constrained Q2 space.

The 2D counterpart of :mod:`dolfinx_ntf.fem.serendipity` (docs/method.md §13.5, §23): the 8-node
serendipity space on a quadrilateral is the biquadratic (9-node) functions whose value at the cell
centre is fixed by the 8 others,

    u(centre) = -1/4 sum(4 corners) + 1/2 sum(4 midside nodes),

the value the serendipity shape functions take there. Local nodes of a dolfinx Q2 quadrilateral:
0..3 the vertices (tensor order), 4..7 the edges (v0-v1, v0-v2, v1-v3, v2-v3), 8 the centre.
"""

from __future__ import annotations

import typing

import numpy as np

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import LinearConstraintBlock

__all__ = [
    "add_quad_centres",
    "has_quad_centres",
    "quad_forces_on_nodes",
    "quad_serendipity_constraints",
]

#: Weights of the centre's value from the 8 local nodes (vertices, then edges).
CENTRE_WEIGHTS = np.array([-0.25] * 4 + [0.5] * 4)


def add_quad_centres(cells: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """9-node cells from 8-node ones (dolfinx order): the cell centres appended to ``x``.

    ``cells`` are ``(C, 8)`` rows into ``x`` (vertices, then edges, dolfinx's order of a Q2
    quadrilateral); each centre is placed by the serendipity map of the 8 nodes. Its rows come
    after those of ``x``.
    """
    centre_x = np.einsum("k,ckd->cd", CENTRE_WEIGHTS, x[cells[:, :8]])
    centre = x.shape[0] + np.arange(cells.shape[0])
    return np.hstack([cells[:, :8], centre[:, None]]), np.vstack([x, centre_x])


def quad_serendipity_constraints(V: dolfinx.fem.FunctionSpace) -> list[LinearConstraintBlock]:
    """The cell-centre constraints that turn a Q2 vector space on quadrilaterals into quad8's.

    Args:
        V: Vector Lagrange space of degree 2 on a quadrilateral mesh (this process's cells,
            ghosts included).

    Returns:
        One block, 9 terms per row (the centre first, the dependent dof), one row per cell and
        component. Dirichlet conditions must leave the centres free.
    """
    if V.mesh.topology.cell_type != dolfinx.mesh.CellType.quadrilateral:
        raise ValueError("quad_serendipity_constraints: a quadrilateral mesh is needed")
    bs = V.dofmap.index_map_bs
    if compat.space_degree(V) != 2:
        raise ValueError("quad_serendipity_constraints: a degree-2 vector space is needed")
    dofs = compat.cell_dofs(V).astype(np.int64)
    if dofs.shape[1] != 9:
        raise ValueError(
            f"quad_serendipity_constraints: 9 dofs per cell expected, got {dofs.shape[1]}"
        )
    nodes = dofs[:, [8, *range(8)]]
    coefficients = np.concatenate([[1.0], -CENTRE_WEIGHTS])
    return [
        LinearConstraintBlock(
            np.repeat(nodes, bs, axis=0),
            np.tile(np.arange(bs), nodes.shape[0])[:, None],
            coefficients,
            name="quad8 cell centres",
            block_size=bs,
        )
    ]


def quad_forces_on_nodes(values: np.ndarray, space: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Element nodal forces of a broken Q2 vector as quad8's: ``(cells, 8, gdim)`` flattened.

    The centre's force moves to the 8 nodes it depends on (virtual work). Owned cells.
    """
    num_owned = space.mesh.topology.index_map(space.mesh.topology.dim).size_local
    dofs = compat.cell_dofs(space)[:num_owned]
    bs = space.dofmap.index_map_bs
    forces = np.asarray(values).reshape(-1, bs)[dofs]  # (cells, 9, bs)
    return (forces[:, :8] + CENTRE_WEIGHTS[None, :, None] * forces[:, 8:9]).ravel()


def has_quad_centres(constraints: typing.Sequence) -> bool:
    """True when ``constraints`` hold the rows of :func:`quad_serendipity_constraints`."""
    row = np.concatenate([[1.0], -CENTRE_WEIGHTS])
    return any(
        isinstance(c, LinearConstraintBlock)
        and c.block_size == 2
        and c.nodes.shape[1] == 9
        and np.allclose(c.coefficients, row)
        for c in constraints
    )
