"""ccx's fallback area held between pairings (``ContactPair(hold_fallback_area=True)``,
docs/method.md §38.5): a faceless slave node's spring takes ``4|m|`` of its master face at the
first evaluation after a pairing and keeps it until the next pairing."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER, LOWER_TOP, UPPER_BOTTOM, YOUNGS_MODULUS, two_blocks
from helpers.blocks import displacement_fields, elastic_residual, punch_conditions

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.kernels.faces import QUAD4, face_tangents

pytestmark = pytest.mark.serial

PUNCH = ((0.2, 0.2, 0.0), (0.6, 0.6, 0.5), (3, 3, 2))


def _problem(hold: bool) -> tuple[ntf.ContactProblem, np.ndarray]:
    """The punch on the block, its bottom's vertices a faceless node set (all springs fall back),
    and the block's nodes."""
    mesh, ct, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH, gap=-1e-3)
    _, u, v, pressure = displacement_fields(mesh)
    vertices = compat.incident_entities(mesh, ft.find(UPPER_BOTTOM), 2, 0)
    pair = ntf.ContactPair(
        ntf.NodeSurface(vertices, faceless=True),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)),
        hold_fallback_area=hold,
    )
    F = elastic_residual(u, v, ft, pressure)
    problem = ntf.ContactProblem(F, u, [pair], punch_conditions(u.function_space, ft))
    return problem, np.unique(compat.cell_dofs(u.function_space)[ct.find(LOWER)])


def _four_m(state, coords: np.ndarray) -> np.ndarray:
    """``4 |q_xi x q_eta|`` of each spring's master face at its projection point at ``coords``."""
    faces = state.master_faces.faces[state.spring_face]
    q_xi, q_eta = face_tangents(QUAD4, coords[faces], state.evaluation.xi)
    return 4.0 * np.linalg.norm(np.cross(q_xi, q_eta), axis=1)


def _stretch_master(problem: ntf.ContactProblem, lower_nodes: np.ndarray) -> None:
    """A displacement stretching the lower block's top in x (its faces' |m| grows)."""
    x = problem.reference_coordinates
    values = problem.u.x.array.reshape(-1, 3)
    lower = np.zeros(x.shape[0], dtype=bool)
    lower[lower_nodes] = True
    values[lower, 0] = 0.1 * x[lower, 0]
    values[~lower, 2] = -2e-3  # the punch a little deeper: every spring stays
    problem.u.x.scatter_forward()


@pytest.mark.parametrize("hold", [True, False])
def test_fallback_area_is_held_until_the_next_pairing(hold):
    problem, lower_nodes = _problem(hold)
    problem.pair()
    (state,) = problem.states
    assert state.num_springs == 16 and np.all(state.spring_area == 0.0)  # all faceless
    problem.evaluate(tangent=False)
    first = state.evaluation.area.copy()
    np.testing.assert_allclose(first, _four_m(state, problem.current_coordinates()), rtol=1e-12)
    _stretch_master(problem, lower_nodes)
    problem.evaluate(tangent=False)
    now = _four_m(state, problem.current_coordinates())
    assert np.all(now > 1.09 * first)  # the master faces grew by 10 % in x
    expected = first if hold else now
    np.testing.assert_allclose(state.evaluation.area, expected, rtol=1e-12)
    problem.pair()  # the next pairing takes the area again, at the stretched master
    problem.evaluate(tangent=False)
    np.testing.assert_allclose(
        state.evaluation.area, _four_m(state, problem.current_coordinates()), rtol=1e-12
    )


def test_hold_fallback_area_must_be_a_bool():
    _, _, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH)
    with pytest.raises(TypeError, match="hold_fallback_area"):
        ntf.ContactPair(
            ntf.FacetSurface(ft, UPPER_BOTTOM),
            ntf.FacetSurface(ft, LOWER_TOP),
            ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)),
            hold_fallback_area="yes",
        )
