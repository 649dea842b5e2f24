"""Cross-validation decks: small contact problems built with dolfinx and exported by ``write_inp``.

Each :class:`Case` writes ``<name>.inp`` into a directory; ``tests/test_ccx_crossval.py`` and
``benchmarks/validate.py`` run ccx and dolfinx_ntf on it and compare. The meshes are structured
boxes (hexahedra, or each hexahedron split into six tetrahedra) stacked along z, with
non-matching grids across each contact interface. Together the cases cover C3D8, C3D4 and
C3D10; the EXPONENTIAL, LINEAR and TABULAR laws; small strain and NLGEOM; several increments;
a curved (warped bilinear) master; face- and node-based slaves; two contact pairs in one deck;
pressure, prescribed-displacement and point loads; an amplitude.

Facet tag of body ``k`` (0-based, bottom to top): ``10 (k + 1) + side`` with the sides below.
Cell tag of body ``k``: ``k + 1``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import ufl
from mpi4py import MPI

import dolfinx.fem
import dolfinx.mesh

import dolfinx_ntf as ntf
from dolfinx_ntf.calculix.writer import (
    TIGHT_FIELD_CONTROLS,
    AmplitudeSpec,
    BoundarySpec,
    OutputSpec,
    PointLoadSpec,
    PressureSpec,
    StepSpec,
    write_inp,
)

__all__ = ["BOTTOM", "TOP", "XMIN", "YMIN", "Case", "CASES", "blocks", "facet_tag"]

BOTTOM, TOP, XMIN, YMIN = 1, 2, 3, 4

#: Output of every deck: displacements of all nodes and every contact print.
_OUTPUT = OutputSpec(node_print=("U",), contact_print=("CDIS", "CSTR", "CELS", "CNUM"))


def facet_tag(body: int, side: int) -> int:
    """Facet tag value of ``side`` of body ``body`` (0-based)."""
    return 10 * (body + 1) + side


@dataclass(frozen=True)
class Case:
    """A cross-validation deck.

    Attributes:
        name: Job name (``<name>.inp``).
        description: One line for the validation report.
        write: ``write(directory)`` writes ``<directory>/<name>.inp``.
        quirk: Known ccx behaviour that limits the comparison (empty if none).
    """

    name: str
    description: str
    write: Callable[[Path], None]
    quirk: str = ""


def _box(origin, size, divisions) -> tuple[np.ndarray, np.ndarray]:
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    nx, ny, _ = divisions
    i, j, k = (a.ravel() for a in np.meshgrid(*(np.arange(n) for n in divisions), indexing="ij"))

    def node(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    hexes = np.column_stack(
        [
            node(i, j, k),
            node(i + 1, j, k),
            node(i, j + 1, k),
            node(i + 1, j + 1, k),
            node(i, j, k + 1),
            node(i + 1, j, k + 1),
            node(i, j + 1, k + 1),
            node(i + 1, j + 1, k + 1),
        ]
    )
    return points, hexes


# Six tetrahedra around the 0-7 diagonal of a hexahedron in dolfinx tensor order (conforming).
_TETS = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 4, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 6, 7)]


def blocks(boxes, *, cell: str = "hexahedron", bump: float = 0.0, degree: int = 1):
    """Boxes ``(origin, size, divisions)`` stacked along z as one mesh (bodies share no nodes).

    Args:
        boxes: One ``(origin, size, divisions)`` per body, bottom to top.
        cell: ``"hexahedron"`` or ``"tetrahedron"``.
        bump: Raise the top of body 0 by ``bump (1 - r^2/R^2)`` (r from the top centre, R half
            its diagonal), fading linearly to zero at its bottom: a curved master.
        degree: Displacement degree (2 only with tetrahedra).

    Returns:
        ``(V, cell_tags, facet_tags)`` on ``MPI.COMM_SELF``.
    """
    points, cells, marker = [], [], []
    offset = 0
    for body, (origin, size, divisions) in enumerate(boxes):
        p, c = _box(origin, size, divisions)
        if body == 0 and bump:
            centre = np.array(origin[:2]) + 0.5 * np.array(size[:2])
            r2 = np.sum((p[:, :2] - centre) ** 2, axis=1) / (0.25 * np.sum(np.array(size[:2]) ** 2))
            p[:, 2] += bump * (1.0 - r2) * (p[:, 2] - origin[2]) / size[2]
        points.append(p)
        cells.append(c + offset)
        marker.append(np.full(c.shape[0], body + 1))
        offset += p.shape[0]
    points, cells, marker = np.vstack(points), np.vstack(cells), np.concatenate(marker)
    if cell == "tetrahedron":
        cells = np.vstack([cells[:, t] for t in _TETS])
        marker = np.tile(marker, len(_TETS))
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", cell, 1))
    mesh = dolfinx.mesh.create_mesh(MPI.COMM_SELF, cells.astype(np.int64), points, domain)
    # create_mesh reorders cells: find each cell's body from its original index.
    body_of_cell = marker[mesh.topology.original_cell_index]
    num_cells = body_of_cell.size
    cell_tags = dolfinx.mesh.meshtags(
        mesh, 3, np.arange(num_cells, dtype=np.int32), body_of_cell.astype(np.int32)
    )
    mesh.topology.create_connectivity(2, 3)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    f_to_c = mesh.topology.connectivity(2, 3)
    body = body_of_cell[f_to_c.array[f_to_c.offsets[exterior]]] - 1
    mid = dolfinx.mesh.compute_midpoints(mesh, 2, exterior)
    values = np.zeros(exterior.size, dtype=np.int32)
    for k, (origin, size, _) in enumerate(boxes):  # loop over a handful of bodies
        mine = body == k
        bottom = np.isclose(mid[:, 2], origin[2])
        xmin, ymin = np.isclose(mid[:, 0], origin[0]), np.isclose(mid[:, 1], origin[1])
        side = (
            xmin
            | ymin
            | np.isclose(mid[:, 0], origin[0] + size[0])
            | np.isclose(mid[:, 1], origin[1] + size[1])
        )
        values[mine & bottom] = facet_tag(k, BOTTOM)
        values[mine & xmin & ~bottom] = facet_tag(k, XMIN)
        values[mine & ymin & ~xmin & ~bottom] = facet_tag(k, YMIN)
        values[mine & ~side & ~bottom] = facet_tag(k, TOP)
    keep = values > 0
    order = np.argsort(exterior[keep])
    facet_tags = dolfinx.mesh.meshtags(mesh, 2, exterior[keep][order], values[keep][order])
    V = dolfinx.fem.VectorFunctionSpace(mesh, ("Lagrange", degree))
    return V, cell_tags, facet_tags


def _rollers(ft, bodies) -> list[BoundarySpec]:
    """Rollers on the planes x = x_min (u_x = 0) and y = y_min (u_y = 0) of the given bodies."""
    specs = []
    for k in bodies:
        specs.append(BoundarySpec(ntf.FacetSurface(ft, facet_tag(k, XMIN)), (0,), name=f"XSYM{k}"))
        specs.append(BoundarySpec(ntf.FacetSurface(ft, facet_tag(k, YMIN)), (1,), name=f"YSYM{k}"))
    return specs


def _pair(
    ft, slave_body: int, master_body: int, law, *, nodal: bool = False, V=None
) -> ntf.ContactPair:
    master = ntf.FacetSurface(ft, facet_tag(master_body, TOP))
    if nodal:
        mesh = V.mesh
        facets = ft.find(facet_tag(slave_body, BOTTOM))
        vertices = dolfinx.mesh.compute_incident_entities(mesh, facets, 2, 0)
        slave = ntf.NodeSurface(vertices, name=f"bottom{slave_body}")
    else:
        slave = ntf.FacetSurface(ft, facet_tag(slave_body, BOTTOM))
    return ntf.ContactPair(slave, master, ntf.SurfaceInteraction(law))


E1, NU1 = 1000.0, 0.3  # lower body
E2, NU2 = 2000.0, 0.25  # upper bodies

LOWER = ((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (4, 4, 2))
PUNCH = ((0.11, 0.13, 0.0), (0.6, 0.6, 0.4), (3, 3, 2))


def _hex_linear_pressure(directory: Path) -> None:
    V, ct, ft = blocks([LOWER, PUNCH])
    law = ntf.LinearLaw(slope=50 * E1, tension=E1 / 70000.0, c0=1e-3)
    steps = [
        StepSpec(
            pressures=[PressureSpec(ntf.FacetSurface(ft, facet_tag(1, TOP)), 20.0)],
            increments=3,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "hex_linear_pressure.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D8 punch on a block, LINEAR law, pressure, 3 increments",
    )


def _tet_exponential_nlgeom(directory: Path) -> None:
    lower = ((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (3, 3, 2))
    punch = ((0.11, 0.13, 0.002), (0.6, 0.6, 0.4), (2, 2, 2))  # starts 0.002 above the block
    V, ct, ft = blocks([lower, punch], cell="tetrahedron")
    law = ntf.ExponentialLaw(c0=0.005, p0=1.0)
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))
    steps = [
        StepSpec(
            boundaries=[BoundarySpec(top, (2,), -0.03, name="PRESS")],
            increments=4,
            nlgeom=True,
            amplitude=AmplitudeSpec((0.0, 0.5, 1.0), (0.0, 0.3, 1.0), name="RAMP"),
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "tet_exponential_nlgeom.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D4 punch with an initial gap, EXPONENTIAL law, NLGEOM, amplitude, 4 increments",
    )


def _hex_tabular_nodal(directory: Path) -> None:
    V, ct, ft = blocks([LOWER, PUNCH])
    law = ntf.TabularLaw(pressures=[0.0, 20.0, 1020.0], overclosures=[0.0, 5e-4, 0.0105])
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))
    steps = [
        StepSpec(
            boundaries=[BoundarySpec(top, (2,), -0.004, name="PRESS")],
            increments=2,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "hex_tabular_nodal.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law, nodal=True, V=V)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D8 punch, node-based slave (TYPE=NODE), TABULAR law, 2 increments",
    )


def _hex_curved_master(directory: Path) -> None:
    lower = ((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (5, 5, 2))
    punch = ((0.13, 0.17, 0.02), (0.7, 0.7, 0.3), (4, 4, 1))  # apex of the bump: z = 0.02
    V, ct, ft = blocks([lower, punch], bump=0.02)
    law = ntf.LinearLaw(slope=50 * E1, tension=E1 / 70000.0, c0=1e-3)
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))
    steps = [
        StepSpec(
            boundaries=[BoundarySpec(top, (2,), -0.01, name="PRESS")],
            increments=4,
            nlgeom=True,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "hex_curved_master.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D8 flat punch on a curved (warped quad) master, LINEAR law, NLGEOM, "
        "growing contact zone, 4 increments",
    )


def _hex_two_pairs(directory: Path) -> None:
    middle = ((0.07, 0.09, 0.0), (0.8, 0.8, 0.3), (3, 3, 1))
    upper = ((0.19, 0.23, 0.3), (0.5, 0.5, 0.3), (3, 3, 1))
    V, ct, ft = blocks([LOWER, middle, upper])
    pairs = [
        _pair(ft, 1, 0, ntf.LinearLaw(slope=50 * E1, tension=E1 / 70000.0, c0=1e-3)),
        _pair(ft, 2, 1, ntf.ExponentialLaw(c0=0.002, p0=5.0)),
    ]
    load_nodes = ntf.FacetSurface(ft, facet_tag(2, TOP))
    steps = [
        StepSpec(
            point_loads=[PointLoadSpec(load_nodes, 2, -0.3, name="LOAD")],
            increments=3,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "hex_two_pairs.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2), 3: (E2, NU2)},
        cell_tags=ct,
        pairs=pairs,
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1, 2]),
        ],
        steps=steps,
        heading="Three stacked C3D8 blocks, two pairs (LINEAR, EXPONENTIAL), point loads, "
        "3 increments",
    )


def _tet_linear_two_steps(directory: Path) -> None:
    V, ct, ft = blocks([LOWER, PUNCH], cell="tetrahedron")
    law = ntf.LinearLaw(slope=50 * E1, tension=E1 / 70000.0, c0=1e-3)
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))
    steps = [
        StepSpec(
            pressures=[PressureSpec(top, 10.0)],
            increments=2,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        ),
        StepSpec(
            pressures=[PressureSpec(top, 30.0)],
            increments=2,
            nlgeom=True,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        ),
    ]
    write_inp(
        directory / "tet_linear_two_steps.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D4 punch, LINEAR law, pressure 10 (small strain) then 30 (NLGEOM)",
    )


def _tet10_exponential(directory: Path) -> None:
    lower = ((0.0, 0.0, -0.5), (1.0, 1.0, 0.5), (2, 2, 1))
    punch = ((0.11, 0.13, 0.0), (0.6, 0.6, 0.4), (2, 2, 1))
    V, ct, ft = blocks([lower, punch], cell="tetrahedron", degree=2)
    law = ntf.ExponentialLaw(c0=0.002, p0=2.0)
    top = ntf.FacetSurface(ft, facet_tag(1, TOP))
    steps = [
        StepSpec(
            pressures=[PressureSpec(top, 20.0)],
            increments=2,
            field_controls=TIGHT_FIELD_CONTROLS,
            output=_OUTPUT,
        )
    ]
    write_inp(
        directory / "tet10_exponential.inp",
        displacement_space=V,
        materials={1: (E1, NU1), 2: (E2, NU2)},
        cell_tags=ct,
        pairs=[_pair(ft, 1, 0, law)],
        fixed=[
            BoundarySpec(ntf.FacetSurface(ft, facet_tag(0, BOTTOM)), name="BASE"),
            *_rollers(ft, [0, 1]),
        ],
        steps=steps,
        heading="C3D10 punch (6-node faces), EXPONENTIAL law, pressure, 2 increments",
    )


CASES: tuple[Case, ...] = (
    Case(
        "hex_linear_pressure",
        "C3D8, LINEAR, face slave, pressure, 3 increments",
        _hex_linear_pressure,
    ),
    Case(
        "tet_exponential_nlgeom",
        "C3D4, EXPONENTIAL, initial gap, NLGEOM, amplitude, 4 increments",
        _tet_exponential_nlgeom,
    ),
    Case(
        "hex_tabular_nodal",
        "C3D8, TABULAR, node-based slave, prescribed displacement, 2 increments",
        _hex_tabular_nodal,
    ),
    Case(
        "hex_curved_master",
        "C3D8, LINEAR, curved master, NLGEOM, growing contact zone, 4 increments",
        _hex_curved_master,
    ),
    Case(
        "hex_two_pairs",
        "C3D8, two pairs (LINEAR + EXPONENTIAL), point loads, 3 increments",
        _hex_two_pairs,
    ),
    Case(
        "tet_linear_two_steps",
        "C3D4, LINEAR, two steps (small strain, then NLGEOM), 2+2 increments",
        _tet_linear_two_steps,
    ),
    Case(
        "tet10_exponential",
        "C3D10, EXPONENTIAL, tri6 faces, pressure, 2 increments",
        _tet10_exponential,
    ),
)
"""Every cross-validation deck."""
