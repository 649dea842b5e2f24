"""Every wrong use of issue 8 fails at the call that makes it, with a message naming the argument,
the value and what is expected (or warns where CalculiX's rule replaces a value); none hangs, none
passes silently, none surfaces a bare AttributeError, IndexError or PETSc error code.

The message fragments matched here are the part a user reads first: the argument and what to do.
"""

import os
import warnings

import numpy as np
import pytest
from helpers import LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, punch_conditions, two_blocks

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial

E = 1000.0


@pytest.fixture(scope="module")
def blocks():
    """Two stacked blocks with a P1 displacement, residual, surfaces and interaction."""
    mesh, _, ft = two_blocks()
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, 0.3), ufl.grad(v)) * ufl.dx
    return {
        "mesh": mesh,
        "ft": ft,
        "V": V,
        "u": u,
        "F": F,
        "slave": ntf.FacetSurface(ft, UPPER_BOTTOM),
        "master": ntf.FacetSurface(ft, LOWER_TOP),
        "interaction": ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E)),
    }


def _pair(b, **changes):
    args = {"slave": b["slave"], "master": b["master"], "interaction": b["interaction"]}
    args.update(changes)
    return ntf.ContactPair(**args)


def _solvable(b):
    """A loaded problem (pressure on the upper top, base clamped) and its solver."""
    mesh, ft, V = b["mesh"], b["ft"], b["V"]
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    F = ufl.inner(ntf.small_strain_stress(u, E, 0.3), ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)
    bcs = punch_conditions(V, ft)
    problem = ntf.ContactProblem(F, u, [_pair(b)], bcs)
    return problem, pressure


# -- surfaces --------------------------------------------------------------------------------------


def test_empty_facet_surface(blocks):
    with pytest.raises(ValueError, match=r"FacetSurface: values is empty; give the facet tag"):
        ntf.FacetSurface(blocks["ft"], [])


def test_facet_surface_with_unknown_tag_or_wrong_values(blocks):
    with pytest.raises(ValueError, match=r"facet tag value\(s\) \[99\] not found"):
        ntf.ContactProblem(
            blocks["F"], blocks["u"], [_pair(blocks, master=ntf.FacetSurface(blocks["ft"], 99))]
        )
    with pytest.raises(TypeError, match=r"values must be integer tag values, but entry 1 is float"):
        ntf.FacetSurface(blocks["ft"], [UPPER_BOTTOM, 1.5])
    with pytest.raises(TypeError, match="tags must be the facet MeshTags"):
        ntf.FacetSurface([1, 2, 3], 1)


def test_node_surface_of_interior_nodes(blocks):
    mesh = blocks["mesh"]
    # The centre line of the lower block, strictly inside it.
    inside = dolfinx.mesh.locate_entities(
        mesh,
        0,
        lambda x: np.isclose(x[0], 0.5) & np.isclose(x[1], 0.5) & (x[2] < -0.1) & (x[2] > -0.9),
    )
    assert inside.size > 0
    with pytest.raises(
        ValueError, match=r"none of its \d+ vertices lies on the boundary of the mesh \(first at"
    ):
        ntf.ContactProblem(
            blocks["F"],
            blocks["u"],
            [_pair(blocks, slave=ntf.NodeSurface(inside, "core"), master=blocks["master"])],
        )
    # Some inside, some on the boundary: a warning that names them.
    top = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[2], 1.0))
    with pytest.warns(UserWarning, match=r"\d+ of its \d+ vertices are inside the mesh"):
        ntf.ContactProblem(
            blocks["F"],
            blocks["u"],
            [_pair(blocks, slave=ntf.NodeSurface(np.concatenate([top, inside])))],
        )


def test_node_surface_indices_must_be_integers_in_range(blocks):
    with pytest.raises(
        ValueError, match=r"vertices must be integer vertex indices, but entry 0 is 0\.5"
    ):
        ntf.NodeSurface([0.5, 3.7])
    with pytest.raises(ValueError, match=r"vertex indices must be >= 0, but entry 1 is -3"):
        ntf.NodeSurface([2, -3])
    with pytest.raises(TypeError, match=r"boolean mask; use np\.flatnonzero"):
        ntf.NodeSurface(np.array([True, False]))
    # Integer-valued floats are indices.
    assert ntf.NodeSurface(np.array([2.0, 3.0])).vertices.tolist() == [2, 3]
    with pytest.raises(ValueError, match=r"vertex index 10000000 \(entry 1\) is outside 0\.\.\d+"):
        ntf.ContactProblem(
            blocks["F"], blocks["u"], [_pair(blocks, slave=ntf.NodeSurface([0, 10**7]))]
        )
    with pytest.raises(ValueError, match="node surface 'nodes' has no vertices"):
        ntf.ContactProblem(blocks["F"], blocks["u"], [_pair(blocks, slave=ntf.NodeSurface([]))])


def test_two_identical_pairs(blocks):
    with pytest.raises(ValueError, match=r"pairs 'pair 1' and 'pair 2' are the same .* remove one"):
        ntf.ContactProblem(blocks["F"], blocks["u"], [_pair(blocks), _pair(blocks)])


def test_pairs_sharing_slave_nodes_and_master_faces_warn(blocks):
    ft = blocks["ft"]
    # The whole upper block surface holds the slave of pair 1: pair 2's slave nodes are among them.
    both = ntf.FacetSurface(ft, [UPPER_BOTTOM, UPPER_TOP])
    with pytest.warns(UserWarning, match=r"share \d+ slave node\(s\) and master faces"):
        ntf.ContactProblem(blocks["F"], blocks["u"], [_pair(blocks), _pair(blocks, slave=both)])


# -- the displacement, the residual, the pairs -----------------------------------------------------


def test_discontinuous_space(blocks):
    W = compat.vector_space(blocks["mesh"], "DG", 1)
    w, v = dolfinx.fem.Function(W), ufl.TestFunction(W)
    F = ufl.inner(ufl.grad(w), ufl.grad(v)) * ufl.dx
    with pytest.raises(
        ValueError,
        match=r"u must be a dolfinx.fem.Function on a vector Lagrange space .* got "
        r"(Discontinuous Lagrange|DQ) degree 1",
    ):
        ntf.ContactProblem(F, w, [_pair(blocks)])


def test_scalar_or_quadratic_spaces(blocks):
    W = compat.scalar_space(blocks["mesh"], "Lagrange", 1)
    w = dolfinx.fem.Function(W)
    F = ufl.inner(ufl.grad(w), ufl.grad(ufl.TestFunction(W))) * ufl.dx
    with pytest.raises(ValueError, match=r"block size 3.*got .*block size 1"):
        ntf.ContactProblem(F, w, [_pair(blocks)])


def test_constant_as_u(blocks):
    c = dolfinx.fem.Constant(blocks["mesh"], np.zeros(3))
    with pytest.raises(
        TypeError, match=r"ContactProblem: u must be a dolfinx.fem.Function .* got Constant"
    ):
        ntf.ContactProblem(blocks["F"], c, [_pair(blocks)])


def test_tuple_instead_of_contact_pair(blocks):
    with pytest.raises(
        TypeError, match=r"ContactProblem: pairs\[0\] must be a ContactPair, got tuple"
    ):
        ntf.ContactProblem(
            blocks["F"], blocks["u"], [(blocks["slave"], blocks["master"], blocks["interaction"])]
        )


def test_law_passed_as_interaction(blocks):
    law = ntf.LinearLaw.with_ccx_defaults(E)
    with pytest.raises(
        TypeError,
        match=r"interaction must be a SurfaceInteraction, got LinearLaw.*"
        r"wrap the law: SurfaceInteraction\(law\)",
    ):
        ntf.ContactPair(blocks["slave"], blocks["master"], law)


def test_wrong_surface_kinds(blocks):
    with pytest.raises(ValueError, match="master surface must be a FacetSurface"):
        ntf.ContactPair(blocks["slave"], ntf.NodeSurface([0]), blocks["interaction"])
    with pytest.raises(
        TypeError, match=r"slave must be a FacetSurface or NodeSurface or FaceNodesSurface, got int"
    ):
        ntf.ContactPair(UPPER_BOTTOM, blocks["master"], blocks["interaction"])
    with pytest.raises(TypeError, match=r"master must be a FacetSurface or FaceNodesSurface or"):
        ntf.ContactPair(blocks["slave"], UPPER_BOTTOM, blocks["interaction"])


def test_bare_contact_pair_instead_of_list(blocks):
    with pytest.raises(
        TypeError,
        match=r"pairs must be a list of ContactPair, got a single ContactPair; pass \[pair\]",
    ):
        ntf.ContactProblem(blocks["F"], blocks["u"], _pair(blocks))


def test_bare_bc_instead_of_list(blocks):
    V = blocks["V"]
    bc = ntf.component_bc(V, 0, blocks["ft"].find(LOWER_BOTTOM))
    with pytest.raises(TypeError, match=r"bcs must be a list of .*got a single .*pass \[bc\]"):
        ntf.ContactProblem(blocks["F"], blocks["u"], [_pair(blocks)], bc)


def test_residual_not_built_on_u(blocks):
    other = dolfinx.fem.Function(blocks["V"])
    v = ufl.TestFunction(blocks["V"])
    F = ufl.inner(ntf.small_strain_stress(other, E, 0.3), ufl.grad(v)) * ufl.dx
    with pytest.raises(ValueError, match="F does not depend on u"):
        ntf.ContactProblem(F, blocks["u"], [_pair(blocks)])
    with pytest.raises(TypeError, match="F must be a UFL form"):
        ntf.ContactProblem(dolfinx.fem.form(F), blocks["u"], [_pair(blocks)])
    with pytest.raises(ValueError, match="linear in one test function"):
        ntf.ContactProblem(ufl.derivative(blocks["F"], blocks["u"]), blocks["u"], [_pair(blocks)])


def test_negative_penalty_slope_warns():
    with pytest.warns(
        UserWarning, match=r"slope = -5\.0 is negative; using ccx's default 50 E = 50000\.0"
    ):
        law = ntf.LinearLaw.with_ccx_defaults(E, slope=-5)
    assert law.slope == 50 * E
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ntf.LinearLaw.with_ccx_defaults(E, slope=0.0)  # zero asks for the default, as in a deck


# -- solving ---------------------------------------------------------------------------------------


def test_nan_in_u_at_a_slave_node(blocks):
    problem, pressure = _solvable(blocks)
    solver = ntf.ContactNewtonSolver(blocks["mesh"].comm, problem)
    node = int(problem.states[0].slave.nodes[3])
    problem.u.x.array[3 * node + 2] = np.nan
    x = problem.reference_coordinates[node]  # the mesh vertex, without round-off
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", t))
    message = (
        rf"u is not finite at 1 node\(s\) of the pair 1 slave surface, first at node {node} "
        rf"\(reference position \({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}\), u = \(0, 0, nan\)\)"
    )
    with pytest.raises(ValueError, match=message):
        step.run(solver, problem.u)


def test_unknown_petsc_solver_names(blocks):
    problem, _ = _solvable(blocks)
    comm = blocks["mesh"].comm
    bad_package = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumsp"}
    with pytest.raises(
        ValueError,
        match=r"pc_factor_mat_solver_type = 'mumsp' is not a name PETSc knows \(known: .*mumps",
    ):
        ntf.ContactNewtonSolver(comm, problem, petsc_options=bad_package)
    with pytest.raises(ValueError, match=r"ksp_type = 'cgg' is not a name PETSc knows"):
        ntf.ContactNewtonSolver(comm, problem, petsc_options={"ksp_type": "cgg"})
    with pytest.raises(TypeError, match="petsc_options must be a dict"):
        ntf.ContactNewtonSolver(comm, problem, petsc_options=["ksp_type", "cg"])
    # Nothing of the failed attempts is left in PETSc's options database.
    from petsc4py import PETSc

    assert not any(key.startswith("ntf_") for key in PETSc.Options().getAll())


def test_solver_and_step_arguments(blocks):
    problem, pressure = _solvable(blocks)
    comm = blocks["mesh"].comm
    with pytest.raises(TypeError, match="ContactNewtonSolver: problem must be a ContactProblem"):
        ntf.ContactNewtonSolver(comm, "problem")
    with pytest.raises(TypeError, match="ContactNewtonSolver: comm must be a Comm"):
        ntf.ContactNewtonSolver(problem, comm)
    with pytest.raises(ValueError, match="max_it must be an integer >= 1, got 0"):
        ntf.ContactNewtonSolver(comm, problem, max_it=0)
    with pytest.raises(
        ValueError, match=r"divergence_rule must be one of \('growth', 'ccx'\), got 'x'"
    ):
        ntf.ContactNewtonSolver(comm, problem, divergence_rule="x")
    with pytest.raises(TypeError, match="set_load must be a function of the step time"):
        ntf.StaticStep(10.0)
    with pytest.raises(ValueError, match=r"min_increment \(0.5\) <= initial_increment \(0.25\)"):
        ntf.StaticStep(lambda t: None, initial_increment=0.25, min_increment=0.5)
    with pytest.raises(ValueError, match="period must be a finite number > 0, got -1"):
        ntf.StaticStep(lambda t: None, period=-1)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", t))
    with pytest.raises(ValueError, match="u must be the Function the ContactProblem was built on"):
        step.run(solver, dolfinx.fem.Function(blocks["V"]))
    with pytest.raises(
        TypeError,
        match=r"StaticStep\.run: solver must be a ContactNewtonSolver or ContactSNESSolver",
    ):
        step.run(problem, problem.u)


def test_writer_on_paths_that_cannot_be_written(blocks, tmp_path):
    problem, _ = _solvable(blocks)
    missing = tmp_path / "no_such_folder" / "out.xdmf"
    with pytest.raises(
        FileNotFoundError,
        match=f"cannot write '{missing}': the folder '{missing.parent}' does not exist",
    ):
        ntf.ContactWriter(problem, missing)
    if os.geteuid() != 0:
        locked = tmp_path / "locked"
        locked.mkdir()
        locked.chmod(0o555)
        with pytest.raises(PermissionError, match=f"cannot write '{locked / 'out.xdmf'}'"):
            ntf.ContactWriter(problem, locked / "out.xdmf")
    # Root writes anywhere permissions would stop others, but not into /proc.
    with pytest.raises(OSError, match=r"ContactWriter: cannot write '/proc/out\.xdmf'"):
        ntf.ContactWriter(problem, "/proc/out.xdmf")


def test_writer_refuses_to_write_after_close(blocks, tmp_path):
    problem, _ = _solvable(blocks)
    writer = ntf.ContactWriter(problem, tmp_path / "out.xdmf")
    writer.write(0.0)
    writer.close()
    writer.close()  # a second close does nothing
    with pytest.raises(
        ValueError, match=r"ContactWriter.write: the writer of .*out\.xdmf is closed"
    ):
        writer.write(1.0)


def test_load_callback_of_the_wrong_shape_is_refused_at_once():
    with pytest.raises(
        TypeError, match=r"StaticStep: set_load must be a function of the step time"
    ):
        ntf.StaticStep(lambda: None)
    with pytest.raises(TypeError, match=r"set_load must be a function of the step time t \(one"):
        ntf.StaticStep(lambda t, scale: None)
    ntf.StaticStep(lambda t, scale=2.0: None)  # defaults are fine
    ntf.StaticStep(print)  # builtins whose signature Python cannot always read are accepted
    assert ntf.StaticStep().set_load(0.5) is None  # no load: increments advance the time only


def test_nan_in_a_prescribed_displacement_is_named(blocks):
    problem, pressure = _solvable(blocks)
    solver = ntf.ContactNewtonSolver(blocks["mesh"].comm, problem)
    compat.boundary_values(problem.bcs[1]).x.array[:] = np.nan  # the punch top's u_x
    with pytest.raises(
        ntf.ContactSolverError, match=r"Dirichlet condition 1 \(of 3\) prescribes \d+ non-finite"
    ):
        ntf.StaticStep(lambda t: setattr(pressure, "value", t)).run(solver, problem.u)


def test_nan_in_the_mesh_geometry_is_named(blocks):
    mesh, _, _ = two_blocks()
    mesh.geometry.x[5, 1] = np.nan
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ntf.small_strain_stress(u, E, 0.3), ufl.grad(v)) * ufl.dx
    with pytest.raises(
        ValueError, match=r"1 node\(s\) with non-finite coordinates \(first: geometry node 5"
    ):
        ntf.ContactProblem(F, u, [], [])
