"""Outputs of 2D contact (plane strain): tables, forces, reactions, fields and XDMF files.

The 2D patch test has a closed form: a pressure p on the upper block's top is carried uniformly
through the contact line, both blocks widen by nu (1 + nu) p / E (plane strain, no lateral
stress), so the contact length is 1 + that strain, the Cauchy pressure p over it, the total
contact force p per unit thickness, and the support under the lower block reacts with the same
force.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import (
    LATERAL_STRAIN,
    LOWER_BOTTOM,
    PRESSURE,
    UPPER_BOTTOM,
    patch_problem,
    solve_patch,
)

import dolfinx.io

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial


@pytest.fixture(scope="module", params=[(1, 1.0), (2, 1.0), (1, 2.5)], ids=["P1", "P2", "t2.5"])
def solved(request):
    """The patch test solved, P1 and P2 per unit thickness, and P1 with thickness 2.5."""
    degree, thickness = request.param
    problem, pressure, ft = patch_problem(MPI.COMM_SELF, degree=degree, thickness=thickness)
    solve_patch(problem, pressure)
    yield problem, ft, thickness
    problem.destroy()


def test_results_table_has_planar_vectors_and_the_closed_form(solved):
    problem, _, thickness = solved
    (res,) = ntf.contact_results(problem)
    degree = compat.space_degree(problem.u.function_space)
    assert res.node.size == 4 * degree + 1  # every slave node, corners and midside nodes
    for name in ("position", "force", "normal", "shear", "slip"):
        assert getattr(res, name).shape == (res.node.size, 2), name
    np.testing.assert_allclose(res.pressure, PRESSURE / (1 + LATERAL_STRAIN), rtol=1e-8)
    assert res.area.sum() == pytest.approx((1 + LATERAL_STRAIN) * thickness, rel=1e-9)
    np.testing.assert_allclose(res.normal, np.tile([0.0, 1.0], (res.node.size, 1)), atol=1e-12)
    assert np.all(res.clearance < 0)
    # The slave nodes are where the displacement puts them.
    u = problem.u.x.array.reshape(-1, 2)[res.node]
    X = problem.u.function_space.tabulate_dof_coordinates()[res.node, :2]
    np.testing.assert_allclose(res.position, X + u, rtol=0, atol=1e-14)
    assert np.all(res.shear == 0) and np.all(res.slip == 0) and not res.sliding.any()


def test_force_area_and_reaction_balance(solved):
    """Contact force = PRESSURE x width x thickness = reaction of the support (round-off)."""
    problem, ft, thickness = solved
    force = ntf.contact_force(problem)
    assert force.shape == (2,)
    assert force[1] == pytest.approx(PRESSURE * thickness, rel=1e-10)
    assert abs(force[0]) <= 1e-10 * force[1]
    assert ntf.contact_area(problem) == pytest.approx((1 + LATERAL_STRAIN) * thickness, rel=1e-9)
    support = ntf.reaction(problem, ft.find(LOWER_BOTTOM))
    assert support.shape == (2,)
    np.testing.assert_allclose(support, force, rtol=0, atol=1e-10 * force[1])
    by_bc = ntf.reaction(problem, dofs=problem.bcs[1])  # the same dofs as a condition
    np.testing.assert_allclose(by_bc, support, rtol=0, atol=1e-12 * force[1])
    # The slave block's nodes: its own springs and load balance (no support there).
    slave = ntf.reaction(problem, ntf.FacetSurface(ft, UPPER_BOTTOM))
    assert np.abs(slave).max() <= 1e-8 * force[1]


def test_fields_hold_the_table_and_the_recovered_pressure(solved):
    problem, _, thickness = solved
    (res,) = ntf.contact_results(problem, recovered=True)
    fields = ntf.ContactFields(problem)
    pressure, clearance, status = fields.at_nodes(res.node)
    np.testing.assert_array_equal(pressure, res.pressure)
    np.testing.assert_array_equal(clearance, res.clearance)
    np.testing.assert_array_equal(status, 1.0)
    assert np.count_nonzero(fields.pressure.x.array) == res.node.size
    assert fields.shear.x.array.size == problem.u.x.array.size
    # p_h per reference length (the measure of the undeformed edges): the load, uniform; its
    # integral is the normal force per unit thickness, whatever the pair's thickness.
    np.testing.assert_allclose(res.recovered_pressure, PRESSURE, rtol=1e-8)
    assert fields.recovery.total() == pytest.approx(PRESSURE, rel=1e-10)
    assert res.normal_force.sum() == pytest.approx(PRESSURE * thickness, rel=1e-10)


def _geometry_values(f: dolfinx.fem.Function) -> np.ndarray:
    """A P1 Function's values at the mesh's geometry nodes (the order XDMF writes them in)."""
    mesh = f.function_space.mesh
    bs = f.function_space.dofmap.index_map_bs
    values = np.zeros((mesh.geometry.x.shape[0], bs))
    values[compat.geometry_dofs(mesh)] = f.x.array.reshape(-1, bs)[
        compat.cell_dofs(f.function_space)
    ]
    return values


def _holds(data: bytes, values: np.ndarray) -> bool:
    """Whether ``data`` holds ``values`` as consecutive little-endian doubles (any alignment).

    To round-off: the writer interpolates to the geometry nodes (a sum of basis values ~1).
    """
    tolerance = 1e-13 * np.abs(values).max()
    for start in range(8):
        doubles = np.frombuffer(data[start : start + (len(data) - start) // 8 * 8], dtype="<f8")
        windows = np.lib.stride_tricks.sliding_window_view(doubles, values.size)
        with np.errstate(invalid="ignore", over="ignore"):  # other bytes as doubles: inf, nan
            if np.any(np.all(np.abs(windows - values) <= tolerance, axis=1)):
                return True
    return False


def test_writer_files_read_back(tmp_path):
    """XDMF: the 2D mesh reads back; every field at every time; the pressures in the h5 file."""
    problem, pressure, _ = patch_problem(MPI.COMM_SELF)
    path = tmp_path / "patch_2d.xdmf"
    with ntf.ContactWriter(problem, path, MPI.COMM_SELF) as writer:
        writer.write(0.0)
        solver = ntf.ContactNewtonSolver(MPI.COMM_SELF, problem)
        step = ntf.StaticStep(
            lambda t: setattr(pressure, "value", PRESSURE * t),
            initial_increment=0.5,
            on_increment=lambda result: writer.write(result.time),
        )
        step.run(solver, problem.u)
        solver.destroy()
        written = {
            f.name: _geometry_values(f)
            for f in (*writer.fields.functions, writer.fields.recovered_pressure)
        }
    mesh = problem.u.function_space.mesh
    with dolfinx.io.XDMFFile(MPI.COMM_SELF, str(path), "r") as xdmf:
        read = xdmf.read_mesh(name="mesh")
    assert read.geometry.dim == 2 and read.topology.dim == 2
    assert read.topology.index_map(2).size_local == mesh.topology.index_map(2).size_local
    np.testing.assert_allclose(
        np.sort(read.geometry.x[:, :2], axis=0), np.sort(mesh.geometry.x[:, :2], axis=0)
    )
    num_nodes = mesh.geometry.x.shape[0]
    grids = {
        grid.get("Name"): grid
        for grid in ET.parse(path).getroot().iter("Grid")
        if grid.get("GridType") == "Collection"
    }
    expected = {
        "contact_pressure": 1,
        "contact_clearance": 1,
        "contact_status": 1,
        "contact_shear": 3,  # XDMF pads 2D vectors to 3 components
        "contact_slip": 3,
        "contact_pressure_recovered": 1,
        problem.u.name: 3,
    }
    assert set(grids) == set(expected)
    for name, components in expected.items():
        steps = grids[name].findall("Grid")
        assert [float(s.find("Time").get("Value")) for s in steps] == [0.0, 0.5, 1.0]
        dims = {s.find("Attribute/DataItem").get("Dimensions") for s in steps}
        assert dims == {f"{num_nodes} {components}"}, name
    # The last step's values are in the h5 file, as written (contiguous little-endian doubles).
    data = path.with_suffix(".h5").read_bytes()
    for name, values in written.items():
        assert np.any(values), name
        assert _holds(data, values.ravel()), name
    assert np.max(written["contact_pressure"]) == pytest.approx(
        PRESSURE / (1 + LATERAL_STRAIN), rel=1e-8
    )
