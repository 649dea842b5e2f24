"""What the demos share: their common options and the bulk problem of the punch geometry.

``dolfinx_ntf.meshes.punch`` makes two bodies: the block (``geometry.BLOCK``, clamped at its
bottom, master top) and the punch (``geometry.PUNCH``, slave bottom, loaded top).
``demos/punch.py``, ``demos/frictional_punch.py`` and ``demos/sliding_block.py`` pose small-strain
elasticity on them with a pressure on the punch top; this module holds that set-up once.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import punch as geometry

__all__ = ["clamped_base_held_top", "demo_parser", "elasticity_with_pressure"]


def demo_parser(doc: str, *, coarse_help: str = "small mesh (tests)") -> argparse.ArgumentParser:
    """The options of every demo (``--coarse``, ``--output``, ``--quiet``); demos add theirs."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help=coarse_help)
    parser.add_argument(
        "--output", type=Path, default=Path("output"), help="output folder (default: output/)"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    return parser


def elasticity_with_pressure(
    mesh: dolfinx.mesh.Mesh,
    cell_tags: compat.MeshTags,
    facet_tags: compat.MeshTags,
    block: tuple[float, float],
    punch: tuple[float, float],
) -> tuple[dolfinx.fem.Function, ufl.Form, dolfinx.fem.Constant]:
    """Small-strain elasticity of both bodies, ``(E, nu)`` each, and a pressure on the punch top.

    The pressure is a Constant (0 until the step scales it); ``n`` is the outward normal, so
    ``p n·v`` in the residual R = f_int - f_ext is a pressure pushing into the punch.

    Returns:
        The displacement (named ``displacement``), the residual form and the pressure Constant.
    """
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V, name="displacement"), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = (
        ufl.inner(small_strain_stress(u, *block), ufl.grad(v)) * dx(geometry.BLOCK)
        + ufl.inner(small_strain_stress(u, *punch), ufl.grad(v)) * dx(geometry.PUNCH)
        + pressure * ufl.inner(ufl.FacetNormal(mesh), v) * ds(geometry.PUNCH_TOP)
    )
    return u, F, pressure


def clamped_base_held_top(
    V: dolfinx.fem.FunctionSpace, facet_tags: compat.MeshTags
) -> list[dolfinx.fem.DirichletBC]:
    """Block bottom clamped; ``u_x = u_y = 0`` on the punch top (its in-plane rigid motions).

    The punch is held vertically by the contact only.
    """
    bottom = facet_tags.find(geometry.BLOCK_BOTTOM)
    top = facet_tags.find(geometry.PUNCH_TOP)
    return [
        dolfinx.fem.dirichletbc(np.zeros(3), dolfinx.fem.locate_dofs_topological(V, 2, bottom), V),
        component_bc(V, 0, top),
        component_bc(V, 1, top),
    ]
