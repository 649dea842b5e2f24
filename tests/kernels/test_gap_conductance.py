"""Tests of the thermal springs and the gap conductance table (kernels/gap_conductance), numpy."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import FACE_TYPES, FaceType, face_points, face_tangents
from dolfinx_ntf.kernels.gap_conductance import GapConductance, evaluate_thermal_springs
from dolfinx_ntf.kernels.laws import LinearLaw
from dolfinx_ntf.kernels.springs import evaluate_springs

SIZE = 2.0  # element size of the test faces
CASES = [("tri3", 0.0), ("quad4", 0.0), ("quad4", 0.15), ("tri6", 0.1), ("quad8", 0.1)]
CASE_IDS = [f"{name}-{'warped' if warp else 'flat'}" for name, warp in CASES]
LAW = LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3)
# Two temperature sets with different pressure points: h depends on p and T everywhere used.
TABLE = GapConductance.from_rows(
    [
        (10.0, 0.0, 100.0),
        (30.0, 20.0, 100.0),
        (45.0, 60.0, 100.0),
        (20.0, 0.0, 400.0),
        (80.0, 50.0, 400.0),
    ]
)


def test_table_interpolation() -> None:
    """Piecewise linear in p, constant outside; linear between temperature sets, else constant."""
    h, dh_dp, dh_dt = TABLE.evaluate([10.0, 40.0, 100.0, 10.0, 10.0], [100, 100, 100, 250, 500])
    at_100 = [20.0, 30.0 + 15.0 * 20 / 40, 45.0]
    np.testing.assert_allclose(h[:3], at_100)
    np.testing.assert_allclose(dh_dp[:3], [1.0, 15.0 / 40, 0.0])
    at_400 = [20.0 + 60.0 * 10 / 50, 20.0 + 60.0 * 40 / 50, 80.0]
    np.testing.assert_allclose(dh_dt[:3], (np.array(at_400) - at_100) / 300)  # right slope
    h_400 = 20.0 + 60.0 * 10 / 50
    np.testing.assert_allclose(h[3], 0.5 * (20.0 + h_400))
    np.testing.assert_allclose(dh_dt[3], (h_400 - 20.0) / 300)
    np.testing.assert_allclose(h[4], h_400)  # above the last temperature: constant
    assert dh_dt[4] == 0.0
    assert np.all(GapConductance.constant(7.0).evaluate([0.0, 1e9], [-5.0, 5.0])[0] == 7.0)


def test_table_derivatives_match_finite_differences() -> None:
    rng = np.random.default_rng(3)
    p, t = rng.uniform(1.0, 70.0, 50), rng.uniform(120.0, 380.0, 50)
    _, dh_dp, dh_dt = TABLE.evaluate(p, t)
    step = 1e-6
    np.testing.assert_allclose(
        dh_dp, (TABLE.evaluate(p + step, t)[0] - TABLE.evaluate(p - step, t)[0]) / (2 * step),
        rtol=1e-6, atol=1e-8,
    )  # fmt: skip
    np.testing.assert_allclose(
        dh_dt, (TABLE.evaluate(p, t + step)[0] - TABLE.evaluate(p, t - step)[0]) / (2 * step),
        rtol=1e-6, atol=1e-8,
    )  # fmt: skip


def test_table_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="pressures must increase"):
        GapConductance.from_rows([(1.0, 5.0, 0.0), (2.0, 1.0, 0.0)])
    with pytest.raises(ValueError, match="temperatures must increase"):
        GapConductance.from_rows([(1.0, 0.0, 10.0), (2.0, 0.0, 5.0)])
    with pytest.raises(ValueError, match="negative conductance"):
        GapConductance.constant(-1.0)
    with pytest.raises(ValueError, match="shape"):
        GapConductance.from_rows([1.0, 2.0])


def _penetrating(ft: FaceType, warp: float, num: int, seed: int):
    """Distorted, warped, tilted faces and slave nodes below interior points of them."""
    rng = np.random.default_rng(seed)
    params = ft.node_parameters * (SIZE if ft.is_triangle else SIZE / 2)
    coords = np.zeros((num, ft.num_nodes, 3))
    coords[:, :, :2] = params + 0.08 * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes, 2))
    coords[:, :, 2] = warp * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes))
    coords[:, :, 2] += 0.3 * coords[:, :, 0]  # tilted
    if ft.is_triangle:
        bary = rng.dirichlet(np.ones(3), num) * 0.55 + 0.15
        xi = (bary / bary.sum(axis=1, keepdims=True))[:, 1:]
    else:
        xi = rng.uniform(-0.6, 0.6, (num, 2))
    t1, t2 = face_tangents(ft, coords, xi)
    normal = np.cross(t1, t2)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    depth = rng.uniform(0.002, 0.05, num) * SIZE
    slave = face_points(ft, coords, xi) - depth[:, None] * normal
    return coords, slave, rng.uniform(0.5, 2.0, num), xi, depth


def _state(name: str, warp: float, seed: int = 2):
    ft = FACE_TYPES[name]
    coords, slave, areas, _, _ = _penetrating(ft, warp, 8, seed=seed)
    rng = np.random.default_rng(seed)
    temperatures = rng.uniform(150.0, 350.0, (8, ft.num_nodes + 1))
    return ft, coords, slave, areas, temperatures


def _thermal(ft, coords, slave, areas, temperatures, *, tangent=True):
    ev = evaluate_springs(ft, coords, slave, areas, LAW, tangent=tangent)
    return evaluate_thermal_springs(
        ft,
        ev.xi,
        temperatures,
        ev.area,
        ev.normal_force / ev.area,
        TABLE,
        tangent=tangent,
        dxi=ev.dxi,
        dpressure=ev.dpressure,
    )


@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_heat_flow_is_conservative(name: str, warp: float) -> None:
    """The master face loses what the slave node gets; q = A h (T_m - T_s)."""
    ft, coords, slave, areas, temperatures = _state(name, warp)
    th = _thermal(ft, coords, slave, areas, temperatures)
    np.testing.assert_allclose(th.residual.sum(axis=1), 0.0, atol=1e-9 * np.abs(th.flow).max())
    assert np.all(th.conductance > 0)
    np.testing.assert_allclose(th.flow, areas * th.conductance * th.temperature_jump)
    np.testing.assert_allclose(th.residual[:, -1], -th.flow)


@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_temperature_tangent_matches_finite_differences(name: str, warp: float) -> None:
    ft, coords, slave, areas, temperatures = _state(name, warp)
    th = _thermal(ft, coords, slave, areas, temperatures)
    step = 1e-5
    fd = np.zeros_like(th.jacobian)
    for k in range(temperatures.shape[1]):
        columns = []
        for sign in (1.0, -1.0):
            t = temperatures.copy()
            t[:, k] += sign * step
            columns.append(_thermal(ft, coords, slave, areas, t, tangent=False).residual)
        fd[:, :, k] = (columns[0] - columns[1]) / (2 * step)
    scale = np.abs(fd).max()
    assert np.abs(th.jacobian - fd).max() <= 1e-7 * scale


@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_displacement_coupling_matches_finite_differences(name: str, warp: float) -> None:
    """∂(heat flows)/∂x through the projection point and the pressure (the coupled tangent)."""
    ft, coords, slave, areas, temperatures = _state(name, warp)
    th = _thermal(ft, coords, slave, areas, temperatures)
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    step = 1e-7 * SIZE
    fd = np.zeros_like(th.coupling)
    for k in range(nodes.shape[1]):
        for c in range(3):
            values = []
            for sign in (1.0, -1.0):
                x = nodes.copy()
                x[:, k, c] += sign * step
                values.append(
                    _thermal(ft, x[:, :-1], x[:, -1], areas, temperatures, tangent=False).residual
                )
            fd[:, :, 3 * k + c] = (values[0] - values[1]) / (2 * step)
    error = np.abs(th.coupling - fd).max(axis=(1, 2)) / np.abs(fd).max(axis=(1, 2))
    assert error.max() <= 1e-5, error
    assert np.abs(fd).max() > 0


def test_bad_temperatures() -> None:
    ft, coords, slave, areas, temperatures = _state("quad4", 0.0)
    temperatures[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"non-finite temperatures at springs \[3\]"):
        _thermal(ft, coords, slave, areas, temperatures)
    with pytest.raises(ValueError, match="temperatures of shape"):
        _thermal(ft, coords, slave, areas, temperatures[:, :3])
