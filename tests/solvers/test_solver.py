"""The Newton solver and step driver on failure: non-retryable errors raise at once with their
cause, a diverging attempt is given up early, and the line search leaves converging solves alone."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import punch_problem

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial


def _step(pressure, load=10.0, **options):
    return ntf.StaticStep(lambda t: setattr(pressure, "value", load * t), **options)


def test_nan_displacement_raises_at_once_naming_the_node():
    problem, pressure, _ = punch_problem("hexahedron")
    problem.u.x.array[7] = np.nan
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    with pytest.raises(ntf.ContactSolverError, match=r"non-finite value\(s\).*first at node 2"):
        _step(pressure).run(solver, problem.u)
    assert solver.updates == 0


def test_nan_load_raises_at_once():
    problem, pressure, _ = punch_problem("hexahedron")
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    with pytest.raises(ntf.ContactSolverError, match="loads, constants and material"):
        _step(pressure, load=np.nan).run(solver, problem.u)


def test_punch_held_only_by_open_contact_stops_at_once():
    """A punch above the block under a load has no support in z: the first solve finds the
    Jacobian singular and the step stops at once, saying why, instead of cutting back."""
    problem, pressure, _ = punch_problem(gap=0.05)
    u = problem.u
    solver = ntf.ContactNewtonSolver(u.function_space.mesh.comm, problem, max_it=30)
    step = _step(pressure, min_increment=0.3)
    with pytest.raises(ntf.ContactSolverError, match=r"Jacobian is singular.*no contact springs"):
        step.run(solver, u)
    assert solver.updates == 0


def test_divergence_rule_gives_up_a_growing_residual():
    """The Python API's rule: from update I_0 on, a residual above the two before it ends the
    attempt; a change of the spring count defers it."""
    from dolfinx_ntf.solvers.convergence import DivergenceRule

    rule = DivergenceRule(4)
    rule.check(3, [1.0, 0.5, 2.0], lambda: "")  # before I_0: no check
    rule.check(4, [1.0, 0.5, 0.9], lambda: "")  # below the larger of the two before
    rule.check(4, [1.0, 0.5, 1.005], lambda: "")  # within DIVERGENCE_GROWTH of it
    rule.defer(4, 4)
    rule.check(5, [1.0, 0.5, 2.0], lambda: "")  # deferred to update 8
    with pytest.raises(ntf.ContactDivergenceError, match=r"residual grows: 1.000e\+00, 5.000e-01"):
        rule.check(8, [1.0, 0.5, 2.0], lambda: "; why")
    rule.reset()
    with pytest.raises(ntf.ContactDivergenceError, match="; why"):
        rule.check(4, [1.0, 0.5, 2.0], lambda: "; why")


def test_line_search_leaves_a_converging_solve_alone():
    problem, pressure, _ = punch_problem("hexahedron")
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    _step(pressure, initial_increment=0.5, fixed=True).run(solver, problem.u)
    assert solver.step_lengths and all(s == 1.0 for s in solver.step_lengths)


def test_line_search_halves_an_overshooting_step():
    """In contact, twice the Newton correction overshoots to about the mirror residual; half of
    it is the Newton step, which the line search takes, leaving x unchanged."""
    problem, pressure, _ = punch_problem("hexahedron")
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    _step(pressure, load=5.0, fixed=True).run(solver, problem.u)
    pressure.value = 6.0
    problem.begin_increment(1.0)
    x = compat.petsc_vector(problem.u)
    problem.form(x)
    problem.F(x, solver.b)
    A = problem.ensure_matrix()
    problem.J(x, A)
    dx = x.duplicate()
    solver.krylov_solver.setOperators(A)
    solver.krylov_solver.solve(solver.b, dx)
    dx.scale(2.0)
    before = x.array.copy()
    assert solver._line_search(dx, x) == 0.5
    np.testing.assert_array_equal(x.array, before)


def test_failed_iterative_solve_falls_back_to_direct_in_the_same_iteration():
    """An iterative solve that does not converge is done again by MUMPS LU in the same Newton
    iteration (no cutback), and LU stays: the run is the direct solver's."""
    runs = {}
    for name, options in (
        ("direct", None),
        ("failing", {"ksp_type": "gmres", "pc_type": "jacobi", "ksp_max_it": 3}),
    ):
        problem, pressure, _ = punch_problem("hexahedron")
        solver = ntf.ContactNewtonSolver(
            problem.u.function_space.mesh.comm, problem, petsc_options=options
        )
        results = _step(pressure, initial_increment=0.5).run(solver, problem.u)
        runs[name] = [(r.attempt, r.iterations) for r in results], problem.u.x.array.copy()
        assert solver.krylov_solver.getType() == "preonly"
    assert runs["failing"][0] == runs["direct"][0] == [(1, 3), (1, 3)]
    assert (
        np.abs(runs["failing"][1] - runs["direct"][1]).max()
        <= 1e-12 * np.abs(runs["direct"][1]).max()
    )


def test_a_stiff_penalty_converges_to_its_round_off():
    """With K = 5e5 E the spring forces carry more round-off than the force-scaled test allows
    (R_n times the mean element force): without the round-off floor every attempt stalls and the
    step gives up; with it (the default) each increment converges in a few iterations."""
    from helpers.blocks import YOUNGS_MODULUS

    outcomes = {}
    for floor in (False, True):
        law = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS, slope=5e5 * YOUNGS_MODULUS)
        problem, pressure, _ = punch_problem("hexahedron", law=law)
        solver = ntf.ContactNewtonSolver(
            problem.u.function_space.mesh.comm, problem, roundoff_floor=floor
        )
        try:
            results = _step(pressure, initial_increment=0.5).run(solver, problem.u)
            outcomes[floor] = [(r.attempt, r.iterations) for r in results]
        except ntf.ContactConvergenceError as error:
            outcomes[floor] = str(error)
    assert "cannot be cut back below the minimum" in outcomes[False]
    assert [attempt for attempt, _ in outcomes[True]] == [1, 1]
    assert all(iterations <= 5 for _, iterations in outcomes[True])


def test_bulk_round_off_under_a_contact_does_not_stall_the_test():
    """A St.Venant-Kirchhoff hemisphere pressed onto a block: its element forces under the contact
    carry more round-off than R_n times the mean element force. With the bulk rows' round-off floor
    (10 eps |K_bulk|_inf max|u|, the default) the first increment converges when the residual
    reaches round-off (6 iterations measured); without any floor it iterates on (14 measured)."""
    import dolfinx.fem
    import ufl

    from dolfinx_ntf.meshes import hertz
    from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

    radius, E, nu = 25.0, 210e3, 0.3
    sizes = {key: value * radius for key, value in hertz.COARSE.items()}
    mesh, _, tags = mesh_from_gmsh(hertz.build_hertz, MPI.COMM_WORLD, radius=radius, **sizes)
    first = {}
    for floor in (True, False):
        V = compat.vector_space(mesh, "Lagrange", 1)
        u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
        lame, shear = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
        deformation = ufl.Identity(3) + ufl.grad(u)
        strain = 0.5 * (deformation.T * deformation - ufl.Identity(3))
        stress = lame * ufl.tr(strain) * ufl.Identity(3) + 2 * shear * strain
        residual = ufl.inner(deformation * stress, ufl.grad(v)) * ufl.dx
        Vz, _ = V.sub(2).collapse()
        top_uz = dolfinx.fem.Function(Vz)
        top = dolfinx.fem.locate_dofs_topological((V.sub(2), Vz), 2, tags.find(hertz.SPHERE_TOP))
        base = dolfinx.fem.locate_dofs_topological(V, 2, tags.find(hertz.BLOCK_BOTTOM))
        bcs = [
            dolfinx.fem.dirichletbc(top_uz, top, V.sub(2)),
            dolfinx.fem.dirichletbc(np.zeros(3), base, V),
            ntf.component_bc(V, 0, tags.find(hertz.SYMMETRY_X)),
            ntf.component_bc(V, 1, tags.find(hertz.SYMMETRY_Y)),
        ]
        law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E, slope=10 * E)
        pair = ntf.ContactPair(
            ntf.FacetSurface(tags, hertz.SPHERE_CONTACT),
            ntf.FacetSurface(tags, hertz.BLOCK_TOP),
            ntf.SurfaceInteraction(law),
        )
        problem = ntf.ContactProblem(residual, u, [pair], bcs)
        with ntf.ContactNewtonSolver(mesh.comm, problem, roundoff_floor=floor) as solver:
            step = ntf.StaticStep(
                lambda t: top_uz.x.array.fill(-0.3 * t), initial_increment=0.25, period=0.25
            )
            first[floor] = step.run(solver, u)[0].iterations
    assert first[True] <= 8 < first[False]
