"""Plane-strain Hertz line contact of two elastic cylinders (benchmarks/hertz_2d.py's model).

The cylinder on a rigid line and on a block are in ``test_rigid_2d.py`` and ``test_contact_2d.py``.
"""

from __future__ import annotations

import hertz_2d
import numpy as np
import pytest

from dolfinx_ntf import compat
from dolfinx_ntf.meshes import cylinder
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh


def test_two_elastic_cylinders_follow_hertz() -> None:
    """R1 = 25 on R2 = 50 at b/10: b within 1 %, p0 within 2 %, contact force = F'/2."""
    result = hertz_2d.run("two-cylinders", 10)
    assert sum(result["iterations"]) <= 40
    assert abs(result["b_error"]) < 1e-2
    assert abs(result["p0_error"]) < 2e-2
    assert result["load_error"] < 1e-8


def test_hertz_line_load_of_two_cylinders_uses_the_relative_radius() -> None:
    """F' for b = R1/20 with 1/R = 1/R1 + 1/R2 and E* of two equal bodies."""
    line_load, b, p0 = hertz_2d.hertz("two-cylinders")
    e_star = hertz_2d.E / (2 * (1 - hertz_2d.NU**2))
    radius = 1 / (1 / hertz_2d.R1 + 1 / hertz_2d.R2)
    assert b == pytest.approx((4 * line_load * radius / (3.141592653589793 * e_star)) ** 0.5)
    assert p0 == pytest.approx(2 * line_load / (3.141592653589793 * b))
    with pytest.raises(ValueError, match="model 'sphere'"):
        hertz_2d.hertz("sphere")


@pytest.mark.parametrize("ratio", [1.0, 0.75])
def test_two_cylinders_mesh_has_its_own_size_on_each_arc(ratio: float) -> None:
    """The lower arc's spacing at the contact is ``lower_size_fine``, the upper's ``size_fine``."""
    size = 0.05
    mesh, _, ft = mesh_from_gmsh(
        cylinder.build_two_cylinders,
        gdim=2,
        radius=1.0,
        lower_radius=2.0,
        size_fine=size,
        lower_size_fine=ratio * size,
        refine_distance=0.2,
    )
    x = mesh.geometry.x
    for tag, expected in ((cylinder.CYLINDER_CONTACT, size), (cylinder.BLOCK_TOP, ratio * size)):
        ends = x[compat.entities_to_geometry(mesh, 1, ft.find(tag))[:, :2]]
        lengths = np.linalg.norm(ends[:, 0] - ends[:, 1], axis=1)
        near = lengths[np.abs(ends[:, :, 0]).max(axis=1) < 0.15]
        assert near.size >= 3
        assert near.mean() == pytest.approx(expected, rel=0.1)


def test_two_cylinders_mesh_refuses_a_bad_size() -> None:
    with pytest.raises(ValueError, match="lower_size_fine must be positive"):
        mesh_from_gmsh(cylinder.build_two_cylinders, gdim=2, lower_size_fine=0.0)
