"""Contact solves give the same results on dolfinx 0.5.2, 0.9 and 0.11 (Debian 12, 13 and sid).

Each supported version's results are stored by ``tests/cross_version_case.py``; this test solves
the cases on the installed version and compares with all stored files to 1e-10.
"""

import numpy as np
import pytest
from cross_version_case import CASES, reference_path, solve

pytestmark = pytest.mark.serial

SUPPORTED = [(0, 5), (0, 9), (0, 11)]


@pytest.fixture(scope="module", params=sorted(CASES))
def case(request):
    return request.param, solve(request.param)


@pytest.mark.parametrize("version", SUPPORTED, ids=lambda v: f"dolfinx-{v[0]}.{v[1]}")
def test_results_match_stored_results_of_each_version(case, version):
    name, current = case
    stored = np.load(reference_path(version))
    np.testing.assert_array_equal(stored[f"{name}/iterations"], current["iterations"])
    np.testing.assert_allclose(stored[f"{name}/coordinates"], current["coordinates"], atol=1e-12)
    np.testing.assert_allclose(
        stored[f"{name}/slave_coordinates"], current["slave_coordinates"], atol=1e-12
    )
    for key in ("displacement", "pressure", "clearance"):
        scale = np.abs(current[key]).max()
        assert scale > 0
        np.testing.assert_allclose(
            stored[f"{name}/{key}"], current[key], rtol=0, atol=1e-10 * scale
        )
