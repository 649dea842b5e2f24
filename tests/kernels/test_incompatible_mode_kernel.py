"""The incompatible-mode hexahedron kernel (C3D8I): patch test, rigid modes, bending, errors."""

from __future__ import annotations

import numpy as np
import pytest

from dolfinx_ntf.kernels.incompatible_modes import (
    condensation,
    condensed_stiffness,
    gauss_point_strains,
    stiffness,
)

CUBE = np.array([[(k & 1), (k >> 1) & 1, (k >> 2) & 1] for k in range(8)], dtype=float)
MU, LMBDA = 80.0, 120.0


def distorted_cells(count: int, seed: int = 0) -> np.ndarray:
    """(count, 8, 3) unit cubes with corners moved up to 0.2 (no longer parallelepipeds)."""
    rng = np.random.default_rng(seed)
    return CUBE[None] + rng.uniform(-0.2, 0.2, (count, 8, 3))


def parallelepipeds(count: int, seed: int = 1) -> np.ndarray:
    """(count, 8, 3) affine images of the unit cube (constant Jacobian)."""
    rng = np.random.default_rng(seed)
    maps = np.eye(3) + rng.uniform(-0.3, 0.3, (count, 3, 3))
    return np.einsum("kj,cij->cki", CUBE, maps) + rng.uniform(-1, 1, (count, 1, 3))


def linear_field(x: np.ndarray, seed: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """(C, 24) nodal values of ``u = G x + b`` and the gradient ``G``."""
    rng = np.random.default_rng(seed)
    gradient = rng.uniform(-1e-3, 1e-3, (3, 3))
    u = x @ gradient.T + rng.uniform(-1, 1, 3)
    return u.reshape(x.shape[0], 24), gradient


@pytest.mark.parametrize(
    ("cells", "taylor"),
    [(distorted_cells(20), True), (parallelepipeds(20), True), (parallelepipeds(20), False)],
    ids=["taylor-distorted", "taylor-parallelepiped", "ccx-parallelepiped"],
)
def test_patch_test(cells: np.ndarray, taylor: bool) -> None:
    """A linear field excites no internal mode and gives the exact constant strain and forces."""
    u, gradient = linear_field(cells)
    condensed = condensation(cells, MU, LMBDA, taylor=taylor)
    alpha = np.einsum("cmd,cd->cm", condensed.recovery, u)
    assert np.abs(alpha).max() < 1e-14
    strain = gauss_point_strains(condensed, u)
    exact = 0.5 * (gradient + gradient.T)
    np.testing.assert_allclose(strain, np.broadcast_to(exact, strain.shape), atol=1e-15)
    # the element forces are those of the trilinear element (which passes the test)
    plain = condensed_stiffness(cells, MU, LMBDA, taylor=taylor) - condensed.correction
    forces = np.einsum("cij,cj->ci", condensed_stiffness(cells, MU, LMBDA, taylor=taylor), u)
    np.testing.assert_allclose(forces, np.einsum("cij,cj->ci", plain, u), atol=1e-13)


def test_ccx_variant_fails_the_patch_test_on_distorted_cells() -> None:
    """CalculiX 2.20's modes (unscaled) pick up linear fields on distorted cells."""
    cells = distorted_cells(20)
    u, _ = linear_field(cells)
    alpha = np.einsum("cmd,cd->cm", condensation(cells, MU, LMBDA, taylor=False).recovery, u)
    assert np.abs(alpha).max() > 1e-6


@pytest.mark.parametrize("taylor", [True, False])
def test_symmetric_with_six_rigid_modes(taylor: bool) -> None:
    """The condensed stiffness is symmetric, positive semidefinite, with a 6-dim null space."""
    cells = distorted_cells(10, seed=4)
    K = condensed_stiffness(cells, MU, LMBDA, taylor=taylor)
    np.testing.assert_allclose(K, np.swapaxes(K, 1, 2), atol=1e-12 * np.abs(K).max())
    eigenvalues = np.linalg.eigvalsh(K)
    scale = eigenvalues[:, -1:]
    assert np.all(np.abs(eigenvalues[:, :6]) < 1e-12 * scale)
    assert np.all(eigenvalues[:, 6:] > 1e-4 * scale)
    # the rigid motions are those null vectors: translations and small rotations
    rotation = np.array([[0, -1, 0.5], [1, 0, -2], [-0.5, 2, 0]])
    rigid = (cells @ rotation.T + [1, 2, 3]).reshape(-1, 24)
    assert np.abs(np.einsum("cij,cj->ci", K, rigid)).max() < 1e-12 * scale.max()


def test_correction_reduces_the_energy() -> None:
    """Condensing internal modes can only soften: the correction is negative semidefinite."""
    correction = condensation(distorted_cells(10, seed=5), MU, LMBDA).correction
    assert np.linalg.eigvalsh(correction).max() < 1e-12 * np.abs(correction).max()


@pytest.mark.parametrize("taylor", [True, False])
def test_pure_bending_is_exact(taylor: bool) -> None:
    """A box in pure bending (nu = 0): the exact strain energy, where the trilinear cell locks.

    ``u = k x z``, ``w = -k x^2 / 2`` has ``e_xx = k z`` only; its energy is ``E k^2 I L / 2``.
    """
    length, height, width, curvature, young = 4.0, 1.0, 0.5, 1e-3, 200.0
    x = (CUBE * [length, width, height] - [0, 0, height / 2])[None]
    u = np.zeros((1, 8, 3))
    u[..., 0] = curvature * x[..., 0] * x[..., 2]
    u[..., 2] = -curvature * x[..., 0] ** 2 / 2
    K = condensed_stiffness(x, young / 2, 0.0, taylor=taylor)
    energy = 0.5 * u.reshape(24) @ K[0] @ u.reshape(24)
    exact = 0.5 * young * curvature**2 * width * height**3 / 12 * length
    np.testing.assert_allclose(energy, exact, rtol=1e-12)
    plain = K - condensation(x, young / 2, 0.0, taylor=taylor).correction
    assert 0.5 * u.reshape(24) @ plain[0] @ u.reshape(24) > 2 * exact  # shear locking


def test_stiffness_matches_a_closed_form() -> None:
    """One unit cube, one field: the isotropic stiffness of two gradients by hand."""
    grad = np.zeros((1, 1, 1, 3))
    grad[..., 0] = 1.0  # a field with gradient e_x
    block = stiffness(grad, grad, np.ones((1, 1)), np.array([MU]), np.array([LMBDA]))[0]
    np.testing.assert_allclose(block, np.diag([LMBDA + 2 * MU, MU, MU]))


def test_bad_cells_are_refused() -> None:
    """Inverted cells and bad shapes raise a clear error naming the cell."""
    cells = distorted_cells(3)
    cells[1] = cells[1][[1, 0, 3, 2, 5, 4, 7, 6]]  # mirrored: det J < 0
    with pytest.raises(ValueError, match="cell 1 has det J"):
        condensation(cells, MU, LMBDA)
    with pytest.raises(ValueError, match=r"\(C, 8, 3\)"):
        condensation(np.zeros((2, 4, 3)), MU, LMBDA)
    with pytest.raises(ValueError, match="finite"):
        condensation(np.full((1, 8, 3), np.nan), MU, LMBDA)
