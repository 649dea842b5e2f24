"""2D contact on several processes gives the serial answer (docs/method.md §14).

Each run is compared with the same problem solved on ``COMM_SELF`` in the same run (a mesh built
once per communicator from the same points and cells): iterations and springs per increment,
the displacement of every node, the table of every spring, the contact force, area and the
support's reaction, and the contact fields written to XDMF. In serial the comparisons are
trivial.
"""

import functools
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import (
    LOWER_BOTTOM,
    PARTITIONS,
    POISSON_RATIO,
    PRESSURE,
    YOUNGS_MODULUS,
    cut_along_x,
    patch_problem,
)
from helpers.serial_answer import sorted_rows

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes import cylinder
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


@dataclass
class Run2D:
    """What a 2D run on one communicator gives, gathered and sorted (the same on every rank)."""

    increments: list[tuple[int, int]]  # Newton iterations and springs of every increment
    nodes: np.ndarray  # reference position and displacement of every node
    springs: np.ndarray  # position, area, pressure, clearance, normal force of every spring
    force: np.ndarray
    area: float
    support: np.ndarray


def _record(problem, results, support_facets) -> Run2D:
    comm = problem.u.function_space.mesh.comm
    owned = problem.u.function_space.dofmap.index_map.size_local
    X = problem.reference_coordinates[:owned, :2]
    nodes = sorted_rows(comm, np.hstack([X, problem.u.x.array.reshape(-1, 2)[:owned]]))
    (table,) = ntf.contact_results(problem)
    springs = sorted_rows(
        comm,
        np.column_stack(
            [table.position, table.area, table.pressure, table.clearance, table.normal_force]
        ),
    )
    return Run2D(
        [(r.iterations, r.springs) for r in results],
        nodes,
        springs,
        ntf.contact_force(problem),
        ntf.contact_area(problem),
        ntf.reaction(problem, support_facets),
    )


def _assert_same(run: Run2D, serial: Run2D) -> None:
    assert run.increments == serial.increments
    np.testing.assert_allclose(run.nodes[:, :2], serial.nodes[:, :2], rtol=0, atol=1e-14)
    scale = np.abs(serial.nodes[:, 2:]).max()
    np.testing.assert_allclose(run.nodes[:, 2:], serial.nodes[:, 2:], rtol=0, atol=1e-10 * scale)
    assert run.springs.shape == serial.springs.shape and serial.springs.shape[0] > 0
    # positions, areas (complete at partition cuts), pressures, clearances and forces
    np.testing.assert_allclose(run.springs, serial.springs, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(run.force, serial.force, rtol=0, atol=1e-10 * serial.force[1])
    assert run.area == pytest.approx(serial.area, rel=1e-10)
    np.testing.assert_allclose(run.support, serial.support, rtol=0, atol=1e-10 * serial.force[1])
    # equilibrium on every process count: the support carries the contact force (vertically;
    # the symmetry line x = 0 takes horizontal reactions too), to Newton's residual
    assert run.support[1] == pytest.approx(run.force[1], rel=1e-8)


def solve_patch_2d(comm, partition, **options) -> Run2D:
    """The 2D blocks (non-matching by default) pressed in two increments."""
    options.setdefault("upper_divisions", 3)
    problem, pressure, ft = patch_problem(comm, partition=partition, **options)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", PRESSURE * t), initial_increment=0.5)
    run = _record(problem, step.run(solver, problem.u), ft.find(LOWER_BOTTOM))
    solver.destroy()
    problem.destroy()
    return run


@functools.lru_cache
def serial_patch_2d(**options) -> Run2D:
    return solve_patch_2d(MPI.COMM_SELF, None, **options)


@pytest.mark.parametrize("partition", PARTITIONS)
def test_nonmatching_blocks_give_the_serial_answer(partition):
    _assert_same(solve_patch_2d(COMM, PARTITIONS[partition]), serial_patch_2d())


@pytest.mark.parametrize("degree", [1, 2])
def test_matching_patch_gives_the_serial_answer(degree):
    """The patch test (uniform pressure) cut through the contact line, P1 and P2."""
    options = {"degree": degree, "upper_divisions": 4}
    run = solve_patch_2d(COMM, cut_along_x, **options)
    _assert_same(run, serial_patch_2d(**options))
    np.testing.assert_allclose(run.springs[:, 3], run.springs[0, 3], rtol=1e-8)
    assert run.force[1] == pytest.approx(PRESSURE, rel=1e-10)


# Plane-strain Hertz (R = 1): the line load for a half-width b = 0.05, b = sqrt(4 F' R/(pi E*)).
E_STAR = YOUNGS_MODULUS / (2 * (1 - POISSON_RATIO**2))
LINE_LOAD = np.pi * E_STAR * 0.05**2 / 4


def cylinder_problem(mesh, ft):
    """Half the line load on the cylinder's top (width R), rollers on x = 0, the block held."""
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    F = ufl.inner(small_strain_stress(u, YOUNGS_MODULUS, POISSON_RATIO), ufl.grad(v)) * ufl.dx
    F += load / 2 * v[1] * ds(cylinder.CYLINDER_TOP)
    law = ntf.LinearLaw(slope=1e4 * YOUNGS_MODULUS, tension=YOUNGS_MODULUS / 70000)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cylinder.CYLINDER_CONTACT),
        ntf.FacetSurface(ft, cylinder.BLOCK_TOP),
        ntf.SurfaceInteraction(law),
    )
    bottom = ft.find(cylinder.BLOCK_BOTTOM)
    bcs = [
        component_bc(V, 0, ft.find(cylinder.SYMMETRY)),
        component_bc(V, 0, bottom),
        component_bc(V, 1, bottom),
    ]
    return ntf.ContactProblem(F, u, [pair], bcs), load


@pytest.mark.parametrize("partition", ["graph", "cut"])
def test_rigid_line_gives_the_serial_answer(partition):
    """The upper block on the rigid line y = 0 (docs/method.md §15.1): one-node springs."""
    run = solve_patch_2d(COMM, PARTITIONS[partition], rigid=True)
    serial = serial_patch_2d(rigid=True)
    assert run.increments == serial.increments
    np.testing.assert_allclose(run.nodes, serial.nodes, rtol=0, atol=1e-10 * PRESSURE)
    assert run.springs.shape == serial.springs.shape == (4, 6)
    np.testing.assert_allclose(run.springs, serial.springs, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(run.force, serial.force, rtol=0, atol=1e-10 * PRESSURE)
    assert run.force[1] == pytest.approx(PRESSURE, rel=1e-8)


def solve_cylinder(comm) -> Run2D:
    """The plane-strain Hertz cylinder on its block (coarse), graph-partitioned."""
    mesh, _, ft = mesh_from_gmsh(
        cylinder.build_cylinder_on_block, comm, gdim=2, size_fine=0.01, refine_distance=0.1
    )
    problem, load = cylinder_problem(mesh, ft)
    solver = ntf.ContactNewtonSolver(comm, problem)
    step = ntf.StaticStep(lambda t: setattr(load, "value", LINE_LOAD * t), initial_increment=0.5)
    run = _record(problem, step.run(solver, problem.u), ft.find(cylinder.BLOCK_BOTTOM))
    solver.destroy()
    problem.destroy()
    return run


@functools.lru_cache
def serial_cylinder() -> Run2D:
    return solve_cylinder(MPI.COMM_SELF)


def test_hertz_cylinder_gives_the_serial_answer():
    """A curved slave on an unstructured mesh; the contact zone cut wherever dolfinx cuts it."""
    run = solve_cylinder(COMM)
    _assert_same(run, serial_cylinder())
    assert run.force[1] == pytest.approx(LINE_LOAD / 2, rel=1e-8)


def test_fields_and_writer_in_parallel(tmp_path_factory):
    """The fields hold each spring's values at owned and ghost nodes; the file has every node."""
    problem, pressure, _ = patch_problem(COMM, partition=cut_along_x, upper_divisions=3)
    solver = ntf.ContactNewtonSolver(COMM, problem)
    ntf.StaticStep(lambda t: setattr(pressure, "value", PRESSURE * t)).run(solver, problem.u)
    solver.destroy()
    folder = COMM.bcast(str(tmp_path_factory.mktemp("out")) if COMM.rank == 0 else None)
    path = f"{folder}/blocks_2d.xdmf"
    with ntf.ContactWriter(problem, path) as writer:
        writer.write(1.0)
        (table,) = ntf.contact_results(problem)
        values = dict(zip(map(tuple, np.round(table.position, 9)), table.pressure))
        values = {k: v for part in COMM.allgather(values) for k, v in part.items()}
        num_local = problem.u.x.array.size // 2
        x = np.round(problem.current_coordinates()[:num_local, :2], 9)
        q = writer.fields._q_of_node
        slave = np.flatnonzero(
            np.isclose(problem.reference_coordinates[:num_local, 1], 0.0)
            & np.isin(np.arange(num_local), problem.states[0].master_faces.nodes, invert=True)
        )
        for node in slave:  # owned and ghost slave nodes: the owner's spring value
            assert writer.pressure.x.array[q[node]] == values[tuple(x[node])]
        assert len(values) == 4  # 3 + 1 slave nodes
        total = writer.fields.recovery.total()
    normal_force = COMM.allreduce(table.normal_force.sum())
    assert total == pytest.approx(normal_force, rel=1e-10)  # p_h carries the normal force
    assert normal_force == pytest.approx(PRESSURE, rel=1e-5)  # to Newton's tolerance
    num_nodes = problem.u.function_space.mesh.topology.index_map(0).size_global  # P1 geometry
    root = ET.parse(path).getroot()
    dims = {
        item.get("Dimensions")
        for grid in root.iter("Grid")
        if grid.get("Name") == "contact_pressure" and grid.get("GridType") == "Uniform"
        for item in grid.iter("DataItem")
    }
    assert dims == {f"{num_nodes} 1"}
    problem.destroy()
