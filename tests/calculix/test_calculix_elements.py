"""The table of ccx element types (dolfinx_ntf.calculix.elements): each entry is consistent."""

from __future__ import annotations

import numpy as np
import pytest

import basix

from dolfinx_ntf.calculix.elements import ELEMENT_TYPES, element_for_cell


@pytest.mark.parametrize("name", list(ELEMENT_TYPES))
def test_node_tables_are_permutations(name):
    etype = ELEMENT_TYPES[name]
    assert sorted(etype.to_dolfinx.tolist()) == list(range(etype.num_nodes))
    assert sorted(etype.mirrored_vertices.tolist()) == list(range(etype.num_corners))
    assert etype.to_dolfinx[etype.corner_vertices].tolist() == list(range(etype.num_corners))
    assert etype.faces.max() < etype.num_nodes and etype.faces.shape[1] in (2, 3, 4, 6, 8)
    assert etype.faces.shape[1] == etype.face_corners + (etype.num_nodes > etype.num_corners) * (
        etype.face_corners if etype.tdim == 3 else 1
    )
    assert len(etype.midside_edges) == etype.num_nodes - etype.num_corners
    # a 27-node space is not C3D20's: no element for degree-2 hexahedra (docs/method.md §13.5);
    # a plain Q1 space is C3D8's, not C3D8I's (no incompatible modes, §22); a 2D cell is several
    # ccx elements (CPE, CPS, CAX): none (the writer is 3D only)
    expected = None if etype.num_nodes == 20 or etype.tdim == 2 else etype
    if name == "C3D8I":
        expected = ELEMENT_TYPES["C3D8"]
    assert element_for_cell(etype.cell, etype.degree) is expected
    assert not etype.faces.flags.writeable and not etype.integration_points.flags.writeable


@pytest.mark.parametrize("name", list(ELEMENT_TYPES))
def test_quadrature_degree_gives_ccx_integration_points(name):
    """The rule the model compiles (basix's default for the degree) is ccx's, point for point."""
    etype = ELEMENT_TYPES[name]
    cell = getattr(basix.CellType, etype.cell)
    points, _ = basix.make_quadrature(cell, etype.quadrature_degree)
    assert points.shape == etype.integration_points.shape

    def rows(x: np.ndarray) -> np.ndarray:
        x = np.round(x, 12)
        return x[np.lexsort(x.T[::-1])]

    np.testing.assert_allclose(rows(points), rows(etype.integration_points), atol=1e-12)


@pytest.mark.parametrize("name", list(ELEMENT_TYPES))
def test_extrapolation_keeps_a_constant_stress(name):
    etype = ELEMENT_TYPES[name]
    assert etype.extrapolation.shape == (etype.num_nodes, etype.integration_points.shape[0])
    # ccx's rounded C3D8 weights (also C3D20R's corners, its midside nodes their means); C3D20's
    # fitted weights write a uniform stress as ccx does, 0.99996 at corners, 1.00005 at midsides
    expected = {"C3D8": 0.99996, "C3D8I": 0.99996, "C3D20R": 0.99996}.get(name, 1.0)
    sums = etype.extrapolation.sum(axis=1)
    if name == "C3D20":
        np.testing.assert_allclose(sums[:8], 0.99996, atol=2e-6)
        np.testing.assert_allclose(sums[8:], 1.00005, atol=2e-6)
    else:
        np.testing.assert_allclose(sums, expected, rtol=1e-12)


@pytest.mark.parametrize("name", [n for n, t in ELEMENT_TYPES.items() if t.tdim == 2])
def test_two_d_faces_are_the_counterclockwise_edges(name):
    """ccx's 2D faces S1.. are the element's edges 1-2, 2-3, ... (manual, quadrilateral faces)."""
    etype = ELEMENT_TYPES[name]
    n = etype.num_corners
    assert etype.faces[:, :2].tolist() == [[k, (k + 1) % n] for k in range(n)]
    if etype.num_nodes > n:  # 6- and 8-node elements: the edge's midside node n + k
        assert etype.faces[:, 2].tolist() == [n + k for k in range(n)]
        assert [tuple(e) for e in etype.midside_edges] == [(k, (k + 1) % n) for k in range(n)]
    assert (
        etype.model
        == {"CPE": "plane strain", "CPS": "plane stress", "CAX": "axisymmetric"}[name[:3]]
    )
    # ccx prints its expanded element's points: each layer repeats the in-plane points (two
    # layers of C3D8, C3D6 and C3D20R, three of C3D15 and C3D20)
    layers = 3 if etype.num_nodes == 6 or etype.name.endswith("8") else 2
    assert etype.print_rows.tolist() == layers * list(range(etype.integration_points.shape[0]))
