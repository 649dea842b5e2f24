"""Wrong input on 2D meshes fails at once, naming the pair (or the step) and what is wrong.

A 2D mesh with a 3-component displacement space, cell or vertex tags given as a facet surface,
facet tags of another mesh (a twin 2D mesh or a 3D one), a rigid circle that moves out of the
plane, a thickness on an axisymmetric pair (named by the pair's name), and a dynamic step whose
mass form is not on the displacement space (docs/guide/two_d.md, "What is refused").
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, two_rectangles

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import small_strain_stress

pytestmark = pytest.mark.serial

E = 1000.0
INTERACTION = ntf.SurfaceInteraction(ntf.LinearLaw(slope=1e4 * E, tension=E / 70000))


@pytest.fixture(scope="module")
def blocks():
    """The two rectangles of the 2D patch test with a P1 displacement and its residual."""
    mesh, ft = two_rectangles(MPI.COMM_SELF)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, 0.3), ufl.grad(v)) * ufl.dx
    return {"mesh": mesh, "ft": ft, "V": V, "u": u, "F": F}


def _pair(slave, master, **options):
    return ntf.ContactPair(slave, master, INTERACTION, **options)


def _space_of_3_components(mesh):
    """A 3-component vector Lagrange space on a 2D mesh (what a 3D script's space gives)."""
    if hasattr(dolfinx.fem, "VectorFunctionSpace"):  # dolfinx 0.5-0.7
        return dolfinx.fem.VectorFunctionSpace(mesh, ("Lagrange", 1), dim=3)
    return dolfinx.fem.functionspace(mesh, ("Lagrange", 1, (3,)))


def test_three_component_space_on_a_2d_mesh(blocks):
    V3 = _space_of_3_components(blocks["mesh"])
    u, v = dolfinx.fem.Function(V3), ufl.TestFunction(V3)
    ft = blocks["ft"]
    pair = _pair(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP))
    with pytest.raises(ValueError, match=r"2D vector displacement space, block size 2.*size 3"):
        ntf.ContactProblem(ufl.inner(u, v) * ufl.dx, u, [pair])


@pytest.mark.parametrize("side", ["slave", "master"])
@pytest.mark.parametrize(("dim", "kind"), [(2, "cell tags"), (0, "vertex tags")])
def test_cell_or_vertex_tags_as_a_facet_surface(blocks, side, dim, kind):
    mesh = blocks["mesh"]
    mesh.topology.create_connectivity(dim, 2)
    entities = dolfinx.mesh.locate_entities(mesh, dim, lambda x: np.isclose(x[1], 0.0) | (x[1] > 0))
    wrong = dolfinx.mesh.meshtags(mesh, dim, entities, np.full(entities.size, 7, dtype=np.int32))
    surfaces = {
        "slave": ntf.FacetSurface(blocks["ft"], UPPER_BOTTOM),
        "master": ntf.FacetSurface(blocks["ft"], LOWER_TOP),
    }
    surfaces[side] = ntf.FacetSurface(wrong, 7)
    pair = _pair(surfaces["slave"], surfaces["master"])
    message = (
        rf"pair 1 {side}: MeshTags of dimension {dim} given \({kind}\), facet tags "
        r"\(dimension 1, the edges of the 2D mesh\) needed"
    )
    with pytest.raises(ValueError, match=message):
        ntf.ContactProblem(blocks["F"], blocks["u"], [pair])


@pytest.mark.parametrize("side", ["slave", "master"])
@pytest.mark.parametrize("other", ["twin 2D mesh", "3D mesh"])
def test_facet_tags_of_another_mesh(blocks, side, other):
    if other == "3D mesh":
        cube = dolfinx.mesh.create_unit_cube(MPI.COMM_SELF, 1, 1, 1)
        facets = dolfinx.mesh.locate_entities_boundary(cube, 2, lambda x: np.isclose(x[2], 0))
        values = np.full(facets.size, UPPER_BOTTOM if side == "slave" else LOWER_TOP)
        tags = dolfinx.mesh.meshtags(cube, 2, facets, values.astype(np.int32))
    else:  # the same rectangles built again: equal, but not the mesh of u
        tags = two_rectangles(MPI.COMM_SELF)[1]
    surfaces = {
        "slave": ntf.FacetSurface(blocks["ft"], UPPER_BOTTOM),
        "master": ntf.FacetSurface(blocks["ft"], LOWER_TOP),
    }
    surfaces[side] = ntf.FacetSurface(tags, UPPER_BOTTOM if side == "slave" else LOWER_TOP)
    pair = _pair(surfaces["slave"], surfaces["master"])
    with pytest.raises(ValueError, match=rf"pair 1 {side}: the facet tags were made on another"):
        ntf.ContactProblem(blocks["F"], blocks["u"], [pair])


def test_the_pairs_own_tags_still_work(blocks):
    """The check compares meshes, not tags: tags made later on the same mesh are accepted."""
    mesh, ft = blocks["mesh"], blocks["ft"]
    again = dolfinx.mesh.meshtags(mesh, 1, ft.indices.copy(), ft.values.copy())
    pair = _pair(ntf.FacetSurface(again, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP))
    problem = ntf.ContactProblem(blocks["F"], blocks["u"], [pair])
    assert problem.states[0].slave.nodes.size == 5


def test_a_rigid_circle_moving_out_of_the_plane(blocks):
    """A sphere centred in z = 0 is a circle; moved along z its normal leaves the plane."""
    circle = ntf.RigidSphere((0.5, 1.0, 0.0), 1.0, motion=lambda t: (0.0, 0.0, 0.5 * t))
    pair = _pair(ntf.FacetSurface(blocks["ft"], UPPER_BOTTOM), circle, name="roller")
    V = blocks["V"]
    u = dolfinx.fem.Function(V)
    F = ufl.inner(small_strain_stress(u, E, 0.3), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    bcs = [
        dolfinx.fem.dirichletbc(
            np.zeros(2), np.arange(V.dofmap.index_map.size_local, dtype=np.int32), V
        )
    ]
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
        with pytest.raises(ValueError, match=r"roller.*must not depend on z.*z component"):
            ntf.StaticStep(lambda t: None, initial_increment=1.0).run(solver, u)


def test_thickness_on_an_axisymmetric_pair_names_the_pair(blocks):
    ft = blocks["ft"]
    with pytest.raises(ValueError, match=r"ContactPair 'seal': an axisymmetric pair has no thick"):
        _pair(
            ntf.FacetSurface(ft, UPPER_BOTTOM),
            ntf.FacetSurface(ft, LOWER_TOP),
            axisymmetric=True,
            thickness=2.0,
            name="seal",
        )


@pytest.mark.parametrize("space", ["P2", "3 components", "scalar"])
def test_dynamic_mass_form_on_another_space(blocks, space):
    mesh, V, u = blocks["mesh"], blocks["V"], blocks["u"]
    W = {
        "P2": lambda: compat.vector_space(mesh, "Lagrange", 2),
        "3 components": lambda: _space_of_3_components(mesh),
        "scalar": lambda: compat.scalar_space(mesh),
    }[space]()
    mass = ufl.inner(ufl.TrialFunction(W), ufl.TestFunction(W)) * ufl.dx
    bottom = dolfinx.fem.locate_dofs_topological(V, 1, blocks["ft"].find(LOWER_BOTTOM))
    problem = ntf.ContactProblem(
        blocks["F"], u, [], [dolfinx.fem.dirichletbc(np.zeros(2), bottom, V)]
    )
    step = ntf.DynamicStep(mass, period=2e-3, initial_increment=1e-3)
    with ntf.ContactNewtonSolver(MPI.COMM_SELF, problem) as solver:
        with pytest.raises(ValueError, match=r"DynamicStep: mass must be a form on the displac"):
            step.run(solver, u)
    assert not problem.extra_terms  # nothing left behind
