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
    assert etype.faces.max() < etype.num_nodes and etype.faces.shape[1] in (3, 4, 6)
    assert len(etype.midside_edges) == etype.num_nodes - etype.num_corners
    assert element_for_cell(etype.cell, etype.degree) is etype
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
    expected = 0.99996 if name == "C3D8" else 1.0  # ccx's rounded C3D8 weights
    np.testing.assert_allclose(etype.extrapolation.sum(axis=1), expected, rtol=1e-12)
