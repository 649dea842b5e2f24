"""The README's Python examples run as written, in order, and do what their comments say."""

import logging
import re
from pathlib import Path

import numpy as np
import pytest

import dolfinx_ntf as ntf
from dolfinx_ntf import logs

pytestmark = pytest.mark.serial

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks() -> list[str]:
    return re.findall(r"^```python\n(.*?)^```$", README.read_text(), flags=re.S | re.M)


def test_readme_examples_run(tmp_path, monkeypatch):
    blocks = _blocks()
    assert len(blocks) == 5
    monkeypatch.chdir(tmp_path)  # the writer's file goes here
    # log_progress() of the example: no stream handler on pytest's capture, levels restored after.
    monkeypatch.setattr(logs, "_handler", logging.NullHandler())
    level, propagate = logs.logger.level, logs.logger.propagate
    namespace: dict = {}
    try:
        for block in blocks:
            exec(compile(block, str(README), "exec"), namespace)
    finally:
        logs.logger.setLevel(level)
        logs.logger.propagate = propagate
    # Pressure loading: the block carries the load of 10 on the 0.4 x 0.4 punch.
    load = 10.0 * 0.4 * 0.4
    problem = namespace["problem"]
    force = ntf.contact_force(problem, "punch")
    assert force[2] == pytest.approx(load, rel=1e-8)
    assert np.abs(force[:2]).max() < 1e-5 * load  # tilted master normals: the rollers take it
    assert ntf.contact_area(problem) == pytest.approx(0.16, rel=1e-2)
    assert [r.time for r in namespace["results"]] == [0.5, 1.0]
    # Prescribed displacement: the reactions at the punch top and the block base balance the
    # contact force, and the writer kept the initial state and both increments.
    problem2 = namespace["problem2"]
    force = ntf.contact_force(problem2)[2]
    assert force > 0
    top = ntf.reaction(problem2, dofs=namespace["top_bc"])
    base = ntf.reaction(problem2, namespace["base_facets"])
    assert top[2] == pytest.approx(-force, rel=1e-8) and not np.any(top[:2])
    assert base[2] == pytest.approx(force, rel=1e-8)
    # Horizontally the base balances the rollers of the punch top.
    rollers = ntf.reaction(problem2, dofs=namespace["bcs"][1:])
    np.testing.assert_allclose(base[:2], -rollers[:2], atol=1e-8 * force)
    assert (tmp_path / "punch.xdmf").read_text().count("Function/contact_pressure/") == 3
    fields = namespace["fields"]
    assert fields.status.x.array.sum() == ntf.contact_results(problem2)[0].node.size
    # Friction and steps: the dragged punch sticks or slips, never beyond mu = 0.5 of the
    # pressure, and its support takes the friction force.
    res3 = namespace["res3"]
    shear = np.linalg.norm(res3.shear, axis=1)
    assert res3.node.size > 0 and shear.max() > 0
    assert np.all(shear <= 0.5 * np.maximum(res3.pressure, 0) * (1 + 1e-10))
    problem3 = namespace["problem3"]
    friction = ntf.contact_force(problem3)
    top = ntf.reaction(problem3, dofs=namespace["bcs3"][1])
    assert friction[0] < 0 and top[0] == pytest.approx(-friction[0], rel=1e-6)
    # Dynamic step: four fixed increments, the punch lands on the block and is slowed down.
    assert [r.increment for r in namespace["dynamic_results"]] == [1, 2, 3, 4]
    assert namespace["problem4"].num_springs > 0
    punch_velocity = namespace["velocity"].x.array.reshape(-1, 3)[namespace["punch_nodes"], 2]
    assert -0.5 < punch_velocity.mean() < 0.0


def test_cited_method_sections_exist():
    """Every "docs/method.md §x" in code, docs and messages names a section of docs/method.md."""
    root = README.parent
    headings = re.findall(
        r"^#{2,3} (\d+(?:\.\d+)?)\.? ", (root / "docs" / "method.md").read_text(), flags=re.M
    )
    sections = set(headings)
    files = [
        *root.glob("dolfinx_ntf/**/*.py"),
        *root.glob("demos/*.py"),
        *(p for p in root.glob("tests/**/*.py") if "data" not in p.parts),
    ]
    files += [*root.glob("benchmarks/*.py"), README, *root.glob("docs/*.md")]
    cited = {}
    for path in files:
        text = path.read_text()
        for match in re.finditer(r"method\.md\s+(§[\d.]+(?:(?:,\s*|\s+and\s+)§[\d.]+)*)", text):
            for number in re.findall(r"§(\d+(?:\.\d+)?)", match.group(1)):
                cited.setdefault(number, path.name)
    assert len(cited) > 20
    missing = {n: f for n, f in cited.items() if n not in sections}
    assert not missing, f"sections cited but not in docs/method.md: {missing}"
