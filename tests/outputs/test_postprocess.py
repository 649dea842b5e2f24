"""Helpers for what users compute after a solve: reactions, contact force and area per pair, the
contact fields as Functions, and the writer (also before the first solve)."""

import numpy as np
import pytest
from helpers import LOWER_BOTTOM, UPPER_TOP, punch_problem

import dolfinx_ntf as ntf
from dolfinx_ntf.outputs.results import RECOVERY_FIELDS

pytestmark = pytest.mark.serial

E, LOAD = 1000.0, 10.0
PUNCH_AREA = 0.6 * 0.6


def _problem(cell="hexahedron"):
    """A punch (0.6 x 0.6) pressed by LOAD on a clamped block; returns problem, pressure, tags."""
    return punch_problem(cell, name="punch")


def _solve(problem, pressure):
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5)
    return step.run(solver, problem.u)


@pytest.fixture(scope="module")
def solved():
    problem, pressure, ft = _problem()
    _solve(problem, pressure)
    return problem, ft


def test_reaction_of_the_clamped_base_carries_the_load(solved):
    problem, ft = solved
    load = LOAD * PUNCH_AREA
    by_facets = ntf.reaction(problem, ntf.FacetSurface(ft, LOWER_BOTTOM))
    # The support pushes the block up with the load; no horizontal reaction (symmetric problem).
    np.testing.assert_allclose(by_facets, [0.0, 0.0, load], atol=1e-9 * load)
    # The same through facet indices or the Dirichlet condition.
    np.testing.assert_allclose(ntf.reaction(problem, ft.find(LOWER_BOTTOM)), by_facets, rtol=1e-12)
    np.testing.assert_allclose(ntf.reaction(problem, dofs=problem.bcs[0]), by_facets, rtol=1e-12)
    np.testing.assert_allclose(
        ntf.reaction(problem, dofs=problem.bcs[0].dof_indices()[0]), by_facets, rtol=1e-12
    )
    # The rollers on the punch top carry nothing; a component condition sums its own component.
    np.testing.assert_allclose(ntf.reaction(problem, dofs=problem.bcs[1:]), 0.0, atol=1e-9 * load)
    # At free dofs the residual vanishes (equilibrium); through the contact surface the full
    # contact force passes (spring forces included).
    np.testing.assert_allclose(
        ntf.reaction(problem, ntf.FacetSurface(ft, UPPER_TOP)), [0, 0, 0], atol=1e-9 * load
    )


def test_contact_force_and_area_per_pair(solved):
    problem, _ = solved
    load = LOAD * PUNCH_AREA
    force = ntf.contact_force(problem)
    np.testing.assert_allclose(force, [0.0, 0.0, load], atol=1e-10 * load)
    for selector in (0, "punch", problem.states[0].pair):
        np.testing.assert_array_equal(ntf.contact_force(problem, selector), force)
    # All 16 punch-bottom nodes are closed: the area is the punch bottom in the current
    # configuration (compressed, it spreads by nu times its strain: measured +0.7 %).
    assert ntf.contact_area(problem, "punch") == pytest.approx(PUNCH_AREA, rel=1e-2)
    with pytest.raises(ValueError, match=r"no pair 'lid' in the problem \(pairs: \['punch'\]\)"):
        ntf.contact_force(problem, "lid")
    with pytest.raises(ValueError, match="no pair 3"):
        ntf.contact_area(problem, 3)
    with pytest.raises(TypeError, match="pair must be an index, a name, a ContactPair or None"):
        ntf.contact_area(problem, 1.5)


def test_reaction_arguments(solved):
    problem, ft = solved
    with pytest.raises(TypeError, match="give either facets or dofs"):
        ntf.reaction(problem)
    with pytest.raises(TypeError, match="give either facets or dofs"):
        ntf.reaction(problem, ft.find(LOWER_BOTTOM), dofs=problem.bcs[0])
    with pytest.raises(
        ValueError, match=r"reaction: dofs: dof index 99999999 \(entry 1\) is outside 0\.\."
    ):
        ntf.reaction(problem, dofs=np.array([0, 99999999]))
    with pytest.raises(TypeError, match="facets must be a 1-D array of integer indices"):
        ntf.reaction(problem, np.array([0.5]))
    with pytest.raises(TypeError, match="reaction: problem must be a ContactProblem"):
        ntf.reaction("problem", ft.find(LOWER_BOTTOM))


def test_contact_fields_are_functions_on_the_nodes(solved):
    problem, _ = solved
    fields = ntf.ContactFields(problem)
    assert [f.name for f in fields.functions] == [
        "contact_pressure",
        "contact_clearance",
        "contact_status",
    ]
    res = ntf.contact_results(problem)[0]
    pressure, clearance, status = fields.at_nodes(res.node)
    np.testing.assert_array_equal(pressure, res.pressure)
    np.testing.assert_array_equal(clearance, res.clearance)
    np.testing.assert_array_equal(status, (res.clearance < 0).astype(float))
    # Zero away from the slave nodes; the pressure integrates to the load with the spring areas.
    assert np.count_nonzero(fields.pressure.x.array) == res.node.size
    assert np.sum(pressure * res.area) == pytest.approx(LOAD * PUNCH_AREA, rel=1e-4)
    assert fields.space.dofmap.index_map_bs == 1


def test_state_before_the_first_solve_and_its_output(tmp_path):
    problem, _, _ = _problem()
    assert [r.node.size for r in ntf.contact_results(problem)] == [0]
    np.testing.assert_array_equal(ntf.contact_force(problem), 0.0)
    assert ntf.contact_area(problem) == 0.0
    np.testing.assert_array_equal(ntf.reaction(problem, dofs=problem.bcs[0]), 0.0)
    path = tmp_path / "initial.xdmf"
    with ntf.ContactWriter(problem, path) as writer:
        writer.write(0.0)  # the initial state, before any solve
        assert not np.any(writer.pressure.x.array)
    assert path.exists() and path.with_suffix(".h5").exists()


def test_writer_writes_every_state(tmp_path):
    problem, pressure, _ = _problem("tetrahedron")
    path = tmp_path / "steps.xdmf"
    with ntf.ContactWriter(problem, path) as writer:
        writer.write(0.0)
        solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
        step = ntf.StaticStep(
            lambda t: setattr(pressure, "value", LOAD * t),
            initial_increment=0.5,
            on_increment=lambda result: writer.write(result.time),
        )
        step.run(solver, problem.u)
        assert writer.status.x.array.sum() == ntf.contact_results(problem)[0].node.size
    text = path.read_text()
    assert text.count("Function/contact_pressure/") == 3  # t = 0, 0.5, 1


def test_recovered_pressure_in_the_results(solved):
    """contact_results(recovered=True): p_h at each slave node (docs/method.md §15.3)."""
    problem, _ = solved
    (plain,) = ntf.contact_results(problem)
    assert plain.recovered_pressure is None
    (res,) = ntf.contact_results(problem, recovered=True)
    assert res.recovered_pressure.shape == res.node.shape
    # p_h carries the whole normal force, and equals what the writer's field holds at the nodes
    total = problem.output_cache[RECOVERY_FIELDS].recovery.total()
    assert total == pytest.approx(res.normal_force.sum(), rel=1e-10)
    fields = ntf.ContactFields(problem)
    np.testing.assert_allclose(
        res.recovered_pressure, fields.recovery.at_nodes(res.node), rtol=1e-12, atol=1e-12
    )
    # quad4 faces: lumped p_h = F_N / (reference face share of the node), the law value F_N / A_p
    # with A_p on the deformed faces (strains of about 1 %): measured 7.3e-3 apart
    assert np.abs(res.recovered_pressure / res.pressure - 1).max() < 1e-2
    (again,) = ntf.contact_results(problem, recovered=True)  # reuses the compiled recovery
    np.testing.assert_array_equal(again.recovered_pressure, res.recovered_pressure)
