"""The README's example runs as written and does what its comments say; its commands exist."""

import logging
import re
from pathlib import Path

import numpy as np
import pytest

import dolfinx_ntf as ntf
from dolfinx_ntf import logs

pytestmark = pytest.mark.serial

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks(language: str = "python") -> list[str]:
    return re.findall(rf"^```{language}\n(.*?)^```$", README.read_text(), flags=re.S | re.M)


def test_readme_example_runs(tmp_path, monkeypatch):
    blocks = _blocks()
    assert len(blocks) == 1
    monkeypatch.chdir(tmp_path)
    # log_progress() of the example: no stream handler on pytest's capture, levels restored after.
    monkeypatch.setattr(logs, "_handler", logging.NullHandler())
    level, propagate = logs.logger.level, logs.logger.propagate
    namespace: dict = {}
    try:
        exec(compile(blocks[0], str(README), "exec"), namespace)
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


def test_readme_commands_and_pointers():
    """The two set-up commands are the Makefile's, and the README says where the docs are built."""
    (commands,) = _blocks("sh")
    lines = [line.split("#")[0].strip() for line in commands.splitlines()]
    assert [line for line in lines if line] == ["make demo", "make test"]
    makefile = (README.parent / "Makefile").read_text()
    assert re.search(r"^demo:", makefile, flags=re.M) and re.search(r"^test:", makefile, flags=re.M)
    # CI's command: make test-all, shown in the README beside the two.
    assert re.search(r"^test-all:", makefile, flags=re.M)
    assert "make test-all" in (README.parent / ".ci" / "run").read_text()
    assert "`make test-all`" in README.read_text()
    docs_rule = re.search(r"^docs:.*\n\t(.*)$", makefile, flags=re.M).group(1)
    assert "sphinx" in docs_rule and docs_rule.endswith("docs docs/_build/html")
    text = README.read_text()
    assert "`make docs`" in text and "docs/_build/html/index.html" in text
    assert "Debian 13 (trixie, dolfinx 0.9.0" in text
    assert "Debian 12 (bookworm, dolfinx 0.5.2" in text
    assert "Debian unstable (sid, dolfinx 0.11" in text


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
