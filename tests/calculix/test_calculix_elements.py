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
    midsides = etype.num_nodes > etype.num_corners
    expected_sizes = etype.face_corner_counts + midsides * (
        etype.face_corner_counts if etype.tdim == 3 else 1
    )
    assert etype.face_sizes.tolist() == expected_sizes.tolist()
    assert np.all(etype.faces[:, : etype.face_sizes.min()] >= 0)
    if name == "C3D15":  # two tri6 faces padded with -1, three quad8 faces
        assert etype.face_corner_counts.tolist() == [3, 3, 4, 4, 4]
    else:
        assert etype.face_sizes.tolist() == [etype.faces.shape[1]] * etype.num_faces
    assert len(etype.midside_edges) == etype.num_nodes - etype.num_corners
    # a 27-node space is not C3D20's: no element for degree-2 hexahedra (docs/method.md §13.5);
    # a plain Q1 space is C3D8's, not C3D8I's (no incompatible modes, §22); a 2D cell is several
    # ccx elements (CPE, CPS, CAX): none (the writer is 3D only)
    # nor an 18-node prism space C3D15's (§34)
    expected = None if etype.num_nodes in (15, 20) or etype.tdim == 2 else etype
    if name == "C3D8I":
        expected = ELEMENT_TYPES["C3D8"]
    assert element_for_cell(etype.cell, etype.degree) is expected
    assert not etype.faces.flags.writeable and not etype.integration_points.flags.writeable


@pytest.mark.parametrize("name", [n for n in ELEMENT_TYPES if n != "C3D15"])
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


def test_c3d15_rule_is_ccx_nine_points():
    """C3D15's custom rule: its points are the printed ones; exact for the triangle's quadratics
    times quintics along the axis (3 triangle points x 3 Gauss points), not beyond."""
    from dolfinx_ntf.calculix.model.c3d15 import c3d15_metadata, c3d15_rule

    points, weights = c3d15_rule()
    np.testing.assert_array_equal(points, ELEMENT_TYPES["C3D15"].integration_points)
    assert c3d15_metadata()["quadrature_weights"] == tuple(weights.tolist())
    x, y, z = points.T

    def exact(i: int, j: int, k: int) -> float:  # the monomial's integral on the prism
        return (
            float(np.prod(np.arange(1, i + 1)) * np.prod(np.arange(1, j + 1)))
            / float(np.prod(np.arange(1, i + j + 3)))
            / (k + 1)
        )

    for i, j, k in [(0, 0, 0), (1, 0, 0), (0, 2, 0), (1, 1, 4), (2, 0, 5), (0, 0, 5)]:
        assert weights @ (x**i * y**j * z**k) == pytest.approx(exact(i, j, k), rel=1e-13)
    assert weights @ z**6 != pytest.approx(exact(0, 0, 6), rel=1e-6)
    assert weights @ x**3 != pytest.approx(exact(3, 0, 0), rel=1e-6)
    # triangle points fastest, then the Gauss layers upwards (ccx's *EL PRINT order)
    assert np.all(np.diff(z.reshape(3, 3), axis=0) > 0) and np.ptp(z[:3]) == 0.0


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
