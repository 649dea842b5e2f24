"""Discrete springs in the Python API (``DiscreteSprings``, docs/method.md §18): closed forms.

A bar of ``nu = 0`` with rollers on three faces is in uniform uniaxial stress under an end
traction, on any mesh and partition, so the springs' closed forms hold to round-off. Four
springs of ``k/4`` on the four corner nodes of a one-cell-wide face carry the force a uniform
traction would: the uniform state stays exact.
"""

from __future__ import annotations

import re
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.mpi

E, LENGTH, FORCE, K = 1000.0, 4.0, 3.0, 500.0  # EA/L = 250 with A = 1


def _bars(starts: list[float]) -> tuple[dolfinx.fem.Function, list, ufl.Form, ufl.Measure]:
    """Unit-section bars of LENGTH along x starting at ``starts``, 4 cells each, one mesh.

    With several bars, bar ``b`` goes to process ``b mod size``: springs between bars join nodes
    of two processes; one bar is partitioned by dolfinx.
    """
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        points, cells = [], []
        for start in starts:
            offset = len(points)
            for i in range(5):
                for j in range(2):
                    for k in range(2):
                        points.append([start + i * LENGTH / 4, j, k])
            for i in range(4):
                v = [offset + 4 * i + 2 * j + k for j in range(2) for k in range(2)]
                cells.append(v + [w + 4 for w in v])  # dolfinx's hexahedron vertex order
        points, cells = np.array(points, float), np.array(cells, np.int64)
        owners = np.repeat(np.arange(len(starts)) % comm.size, 4)
    else:
        points, cells = np.zeros((0, 3)), np.zeros((0, 8), np.int64)
        owners = np.zeros(0, np.int32)
    if len(starts) == 1:
        owners = None
    mesh = compat.create_mesh(
        comm, cells, points, compat.coordinate_element("hexahedron"), owners=owners
    )
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    bcs = []
    for axis, where in ((0, lambda x: np.isclose(x[0], starts[0])), (1, None), (2, None)):
        locate = where or (lambda x, a=axis: np.isclose(x[a], 0.0))
        dofs = dolfinx.fem.locate_dofs_geometrical((V.sub(axis), V.sub(axis).collapse()[0]), locate)
        zero = dolfinx.fem.Function(V.sub(axis).collapse()[0])
        bcs.append(dolfinx.fem.dirichletbc(zero, dofs, V.sub(axis)))
    end = starts[-1] + LENGTH
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], end))
    tags = dolfinx.mesh.meshtags(mesh, 2, facets, np.full(facets.size, 1, np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    eps = ufl.sym(ufl.grad(u))
    sigma = E * eps  # nu = 0
    v = ufl.TestFunction(V)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx - FORCE * v[0] * ds(1)
    return u, bcs, F, ds


def _solve(u, bcs, F, springs) -> ntf.ContactProblem:
    """Solve in one increment; the problem for outputs (the caller destroys it)."""
    problem = ntf.ContactProblem(F, u, [], bcs)
    problem.element_terms.extend(springs)
    solver = ntf.ContactNewtonSolver(u.function_space.mesh.comm, problem)
    ntf.StaticStep(fixed=True, initial_increment=1.0).run(solver, u)
    return problem


def _end_displacement(u: dolfinx.fem.Function, x_end: float) -> np.ndarray:
    """The x displacements at the nodes of the plane x = x_end (over all processes)."""
    V = u.function_space
    owned = V.dofmap.index_map.size_local
    x = V.tabulate_dof_coordinates()[:owned]
    values = u.x.array[: 3 * owned].reshape(-1, 3)[np.isclose(x[:, 0], x_end), 0]
    return np.concatenate(MPI.COMM_WORLD.allgather(values))


CORNERS = [[LENGTH, 0, 0], [LENGTH, 1, 0], [LENGTH, 0, 1], [LENGTH, 1, 1]]


@pytest.mark.parametrize("kind", ["directional", "axial_ground", "tabular", "parallel"])
def test_bar_on_a_spring(kind: str) -> None:
    """Bar fixed at x = 0, spring to ground at x = L: u = F / (k + EA/L)."""
    u, bcs, F, _ = _bars([0.0])
    V = u.function_space
    law = ntf.LinearSpringLaw(K / 4)
    if kind == "directional":  # SPRING1 in x
        springs = ntf.DiscreteSprings(V, ntf.DirectionalSpring(law, (1.0, 0.0, 0.0)), CORNERS)
    elif kind == "axial_ground":  # SPRINGA to a fixed anchor one unit back along x
        anchors = np.array(CORNERS) - [1.0, 0.0, 0.0]
        springs = ntf.DiscreteSprings(V, ntf.AxialSpring(law), CORNERS, anchors, ground=True)
    elif kind == "parallel":  # SPRINGA beside the bar, from its loaded end to its fixed end
        start = np.array(CORNERS) - [LENGTH, 0.0, 0.0]
        springs = ntf.DiscreteSprings(V, ntf.AxialSpring(law), CORNERS, start)
    else:  # a table that is linear with slope k/4 over the range reached
        table = ntf.TabularSpringLaw([-1.0, 0.0, 1.0], [-K / 4, 0.0, K / 4])
        springs = ntf.DiscreteSprings(V, ntf.DirectionalSpring(table, (1.0, 0.0, 0.0)), CORNERS)
    problem = _solve(u, bcs, F, [springs])
    expected = FORCE / (K + E / LENGTH)
    values = _end_displacement(u, LENGTH)
    assert values.size == 4
    np.testing.assert_allclose(values, expected, rtol=1e-10)
    # the support at x = 0 takes all of F only when the springs ending there count
    support = ntf.reaction(problem, dofs=bcs[0])[0]
    carried = FORCE if kind == "parallel" else FORCE * (E / LENGTH) / (K + E / LENGTH)
    assert support == pytest.approx(-carried, rel=1e-10)
    problem.destroy()


def test_two_bars_joined_by_springs() -> None:
    """Bar 1 fixed, bar 2 loaded, joined by axial springs: u = F L/EA + F/k + F L/EA."""
    gap = 1.5
    u, bcs, F, _ = _bars([0.0, LENGTH + gap])
    first = np.array(CORNERS)
    second = first + np.array([gap, 0.0, 0.0])
    springs = ntf.DiscreteSprings(
        u.function_space, ntf.AxialSpring(ntf.LinearSpringLaw(K / 4)), first, second
    )
    if MPI.COMM_WORLD.size > 1:  # the springs join nodes of two processes
        assert MPI.COMM_WORLD.allreduce(int(springs.mine.sum())) == 4
        assert springs.mine.all() == (MPI.COMM_WORLD.rank == 0)
    _solve(u, bcs, F, [springs]).destroy()
    flexibility = 2 * LENGTH / E + 1 / K
    np.testing.assert_allclose(
        _end_displacement(u, 2 * LENGTH + gap), FORCE * flexibility, rtol=1e-10
    )
    np.testing.assert_allclose(_end_displacement(u, LENGTH), FORCE * LENGTH / E, rtol=1e-10)


def test_a_point_off_the_mesh_is_refused() -> None:
    u, _, _, _ = _bars([0.0])
    law = ntf.LinearSpringLaw(1.0)
    with pytest.raises(TypeError, match="AxialSpring or a DirectionalSpring"):
        ntf.DiscreteSprings(u.function_space, law, [[0, 0, 0]])
    with pytest.raises(ValueError, match="same shape"):
        ntf.DiscreteSprings(u.function_space, ntf.AxialSpring(law), [[0, 0, 0]], np.zeros((2, 3)))
    with pytest.raises(ValueError, match=r"finite \(S, 3\) coordinates"):
        ntf.DiscreteSprings(u.function_space, ntf.AxialSpring(law), [[0, 0]])
    with pytest.raises(ValueError, match=r"end 2 of spring 1.*not a node"):
        ntf.DiscreteSprings(
            u.function_space,
            ntf.AxialSpring(ntf.LinearSpringLaw(1.0)),
            [[0, 0, 0], [0, 1, 0]],
            [[1, 0, 0], [1, 0.5, 0]],
        )


def test_guide_example_runs() -> None:
    """The guide page's bar on a spring (docs/guide/springs.md) runs and moves F/(k + EA/L)."""
    text = (Path(__file__).parents[2] / "docs" / "guide" / "springs.md").read_text()
    (block,) = re.findall(r"^```python\n(.*?)^```$", text, flags=re.S | re.M)
    namespace: dict = {}
    exec(compile(block, "docs/guide/springs.md", "exec"), namespace)
    expected = namespace["force"] / (namespace["k"] + namespace["E"] / 4.0)
    np.testing.assert_allclose(namespace["end_u"], expected, rtol=1e-10)
    namespace["problem"].destroy()


def test_assembled_jacobian_matches_finite_differences() -> None:
    """The problem's Jacobian with inclined axial springs across processes: J d against FD of F.

    A St.Venant-Kirchhoff bulk and springs on their current line at a random displacement; the
    direction ``d`` is zero at the Dirichlet dofs (their columns are left out by design).
    """
    gap = 1.5
    u, bcs, _, _ = _bars([0.0, LENGTH + gap])
    V = u.function_space
    first = np.array(CORNERS)
    second = first[[1, 0, 3, 2]] + np.array([gap, 0.0, 0.0])  # crossed: inclined lines
    law = ntf.TabularSpringLaw([-1.0, 0.0, 0.5, 2.0], [-300.0, 0.0, 100.0, 150.0])
    springs = ntf.DiscreteSprings(V, ntf.AxialSpring(law), first, second)
    v = ufl.TestFunction(V)
    G = ufl.Identity(3) + ufl.grad(u)
    strain = 0.5 * (G.T * G - ufl.Identity(3))
    F = ufl.inner(G * (E * strain), ufl.grad(v)) * ufl.dx  # St.Venant-Kirchhoff, nu = 0
    problem = ntf.ContactProblem(F, u, [], bcs)
    problem.element_terms.append(springs)
    rng = np.random.default_rng(7 + MPI.COMM_WORLD.rank)
    x = compat.petsc_vector(u)
    x.array[:] = 0.05 * rng.normal(size=x.array.size)
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    for bc in bcs:  # the random state keeps the conditions
        dolfinx.fem.petsc.set_bc(x, [bc])
    x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
    d = x.duplicate()
    d.array[:] = rng.normal(size=d.array.size)
    fixed = np.concatenate([bc.dof_indices()[0] for bc in bcs])
    d.array[fixed[fixed < d.getLocalSize()]] = 0.0
    A = problem.ensure_matrix()
    problem.form(x)
    problem.assemble_jacobian(x, A)
    Jd = d.duplicate()
    A.mult(d, Jd)

    x0 = x.array_r.copy()

    def residual(step: float) -> np.ndarray:
        """F at x0 + step d (the forms read u, whose vector x is)."""
        x.array[:] = x0 + step * d.array_r
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        b = x.duplicate()
        problem.form(x)
        problem.assemble_residual(x, b)
        values = b.array_r.copy()
        b.destroy()
        return values

    h = 1e-6
    fd = (residual(h) - residual(-h)) / (2 * h)
    scale = MPI.COMM_WORLD.allreduce(float(np.abs(Jd.array_r).max(initial=0.0)), op=MPI.MAX)
    error = MPI.COMM_WORLD.allreduce(float(np.abs(fd - Jd.array_r).max(initial=0.0)), op=MPI.MAX)
    assert scale > 0.0 and error <= 1e-6 * scale
    assert MPI.COMM_WORLD.allreduce(int(springs.mine.sum())) == 4
    for vec in (d, Jd):
        vec.destroy()
    problem.destroy()
