"""The documentation site builds without a warning and its pages render in a browser.

``make docs-check`` runs this file (``make test`` runs ``docs-check``); the serial suite of
``make test-here`` leaves it out (marker ``docs``) so the site is built once per ``make test``.
The build runs the demos on their coarse meshes (sphinx-gallery), then headless Chromium opens the
index, a user-guide page, the API page of ``ContactProblem`` and a demo page from a local HTTP
server: each page's text must be there, every image must have loaded, and no Markdown may be left
unrendered. Screenshots go to ``docs/_build/screenshots/``.
"""

import functools
import html
import http.server
import itertools
import json
import re
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import pytest

import dolfinx_ntf
import dolfinx_ntf.calculix

pytestmark = [pytest.mark.serial, pytest.mark.docs]

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SCREENSHOTS = DOCS / "_build" / "screenshots"

#: Page -> texts it must show (outside code blocks or inside).
PAGES = {
    "index.html": ["Node-to-face penalty contact", "User guide", "API reference"],
    "guide/surfaces.html": ["Surfaces and pairs", "Meshes and facet tags", "FacetSurface"],
    "api/dolfinx_ntf.ContactProblem.html": [
        "ContactProblem",
        "Parameters",
        "walk_from_previous_face",
        "Nonlinear problem",
    ],
    "demos/hertz_sphere.html": [
        "Hertz",
        "Total contact force F",
        "contact radius, fit",
        "the deformed mesh coloured by the contact pressure",
    ],
}
#: What Markdown or MyST left unrendered looks like in a page's text (code blocks excluded).
RAW_MARKDOWN = re.compile(r"```|\{(ref|doc|class|func|mod)\}`|\]\(|^#{1,4} |\*\*\w", re.M)

CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
    "--hide-scrollbars",
]

# Loads each page in an iframe of the same origin and reports its text (without code blocks),
# the full text and, for every image, whether it loaded.
CHECKER = """<!DOCTYPE html><html><body><script>
const pages = %s;
function check(page) {
  return new Promise((resolve) => {
    const frame = document.createElement("iframe");
    frame.style.width = "1280px"; frame.style.height = "1000px";
    frame.onload = () => {
      const doc = frame.contentDocument;
      const prose = doc.body.cloneNode(true);
      prose.querySelectorAll("pre, code, script, style").forEach((e) => e.remove());
      resolve({
        page: page,
        title: doc.title,
        text: doc.body.innerText,
        prose: prose.textContent,
        images: [...doc.images].map((i) => ({src: i.getAttribute("src"),
                                             loaded: i.complete && i.naturalWidth > 0})),
      });
    };
    frame.src = page;
    document.body.appendChild(frame);
  });
}
(async () => {
  const out = [];
  for (const page of pages) out.push(await check(page));
  const pre = document.createElement("pre");
  pre.id = "result";
  pre.textContent = JSON.stringify(out);
  document.body.appendChild(pre);
})();
</script></body></html>
"""


# The page in a frame as tall as the page, shifted up so that its first gallery figure is in the
# window (scrolling inside the frame is not reliable in a headless screenshot).
FIGURE = """<!DOCTYPE html><html><body style="margin:0;overflow:hidden"><iframe id="page" src="%s"
style="border:0;width:1280px;height:40000px;display:block"></iframe><script>
const frame = document.getElementById("page");
frame.onload = () => {
  const figure = frame.contentDocument.querySelector("img[src*='sphx_glr_']");
  if (figure) frame.style.marginTop = (400 - figure.getBoundingClientRect().top) + "px";
};
</script></body></html>
"""


def _chromium() -> str:
    for name in ("chromium", "chromium-browser"):
        if path := shutil.which(name):
            return path
    raise AssertionError("chromium is not installed: run `make setup` (scripts/setup.sh)")


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built as ``make docs`` builds it (warnings are errors), into a fresh directory."""
    out = tmp_path_factory.mktemp("docs") / "html"
    cmd = [sys.executable, "-m", "sphinx", "-b", "html", "-n", "-W", "--keep-going", "-E"]
    run = subprocess.run(
        [*cmd, str(DOCS), str(out)], cwd=ROOT, capture_output=True, text=True, timeout=900
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-6000:]
    return out


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args: object) -> None:
        pass


@pytest.fixture(scope="module")
def server(site):
    """A local HTTP server of the built site (pages in iframes need one origin)."""
    handler = functools.partial(_QuietHandler, directory=str(site))
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{httpd.server_address[1]}"
    httpd.shutdown()
    httpd.server_close()


def _browser(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    profile = tmp_path / "chromium-profile"
    cmd = [_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={profile}", *args]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=180)


def test_every_public_name_has_an_api_page(site):
    for module in (dolfinx_ntf, dolfinx_ntf.calculix):
        names = [n for n in module.__all__ if not n.startswith("__")]
        pages = {p.name for p in (site / "api").glob(f"{module.__name__}.*.html")}
        missing = [n for n in names if f"{module.__name__}.{n}.html" not in pages]
        assert not missing, f"no API page for {missing}"
        index = (site / "api" / "index.html").read_text()
        assert all(f'href="{module.__name__}.{n}.html"' in index for n in names)
    # The count against __all__: one page per name, nothing left over.
    total = sum(
        len([n for n in m.__all__ if not n.startswith("__")])
        for m in (dolfinx_ntf, dolfinx_ntf.calculix)
    )
    pages = [p for p in (site / "api").glob("dolfinx_ntf.*.html") if p.stem.count(".") >= 1]
    named = [
        p
        for p in pages
        if p.stem.rsplit(".", 1)[-1] in set(dolfinx_ntf.__all__) | set(dolfinx_ntf.calculix.__all__)
    ]
    assert len(named) == total


def test_demo_pages_show_their_figures(site):
    for demo in (
        "hertz_sphere",
        "hertz_cylinder_2d",
        "impact",
        "sliding_block",
        "sliding_block_2d",
        "frictional_punch",
        "hot_block",
        "plastic_indentation",
    ):
        page = (site / "demos" / f"{demo}.html").read_text()
        images = re.findall(r'<img[^>]+src="([^"]+)"', page)
        figures = [src for src in images if f"sphx_glr_{demo}_" in src]
        assert figures, f"{demo}: no figure on its page"
        for src in figures:
            assert (site / "demos" / src).stat().st_size > 10_000, src
    # The Hertz page shows the deformed mesh coloured by the contact pressure: the very PNG the demo
    # wrote in this build (its first figure), beside the pressure-against-radius plot.
    page = (site / "demos" / "hertz_sphere.html").read_text()
    figures = [src for src in re.findall(r'<img[^>]+src="([^"]+)"', page) if "sphx_glr_" in src]
    written = DOCS / "_build" / "demo-output" / "hertz_sphere"
    for name, src in zip(("hertz_deformed.png", "hertz_pressure.png"), figures, strict=True):
        assert (site / "demos" / src).read_bytes() == (written / name).read_bytes(), (name, src)


def test_pages_render_in_chromium(site, server, tmp_path):
    (site / "_check.html").write_text(CHECKER % json.dumps(list(PAGES)))
    run = _browser(tmp_path, "--virtual-time-budget=60000", "--dump-dom", f"{server}/_check.html")
    match = re.search(r'<pre id="result">(.*?)</pre>', run.stdout, flags=re.S)
    assert match, f"the checker page did not finish: {run.stdout[-2000:]} {run.stderr[-2000:]}"
    results = json.loads(html.unescape(match.group(1)))
    assert [r["page"] for r in results] == list(PAGES)
    for result in results:
        page = result["page"]
        assert "404" not in result["title"], page
        for text in PAGES[page]:
            # innerText applies the theme's text-transform (field names are upper case)
            assert text.lower() in result["text"].lower(), f"{page}: '{text}' not shown"
        assert not RAW_MARKDOWN.search(result["prose"]), (
            f"{page}: unrendered Markdown: {RAW_MARKDOWN.search(result['prose']).group(0)!r}"
        )
        assert result["images"] or page != "demos/hertz_sphere.html", f"{page}: no image"
        broken = [i["src"] for i in result["images"] if not i["loaded"]]
        assert not broken, f"{page}: images not loaded: {broken}"

    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    # The demo page twice: its top, and scrolled to its figure (a frame of the page).
    (site / "_figure.html").write_text(FIGURE % "demos/hertz_sphere.html")
    for page in [*PAGES, "_figure.html"]:
        name = page.replace("/", "_").replace(".html", "")
        name = "demos_hertz_sphere-figure" if page == "_figure.html" else name
        shot = SCREENSHOTS / f"{name}.png"
        shot.unlink(missing_ok=True)
        run = _browser(
            tmp_path,
            "--window-size=1280,1600",
            "--virtual-time-budget=10000",
            f"--screenshot={shot}",
            f"{server}/{page}",
        )
        assert shot.exists() and shot.stat().st_size > 20_000, (page, run.stderr[-2000:])


def _python_blocks(page: str) -> list[str]:
    text = (DOCS / page).read_text()
    return re.findall(r"^```python\n(.*?)^```$", text, flags=re.S | re.M)


def test_guide_examples_run(tmp_path, monkeypatch):
    """The quick start and the guide's examples run in the order a reader meets them."""
    import logging

    from mpi4py import MPI

    import numpy as np

    from dolfinx_ntf import logs
    from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

    quick = _python_blocks("quickstart.md")
    steps = _python_blocks("guide/steps.md")
    outputs = _python_blocks("guide/outputs.md")
    order = [
        ("quickstart.md", quick[0]),
        *(("guide/modes.md", block) for block in _python_blocks("guide/modes.md")),
        ("guide/laws.md", _python_blocks("guide/laws.md")[0]),
        ("guide/steps.md", steps[0]),
        *(("guide/outputs.md", block) for block in outputs),
        ("guide/friction.md", _python_blocks("guide/friction.md")[0]),
        ("guide/steps.md", steps[1]),
        ("guide/steps.md", steps[2]),
        ("guide/steps.md", steps[3]),
        ("guide/surfaces.md", _python_blocks("guide/surfaces.md")[0]),
        ("guide/surfaces.md", _python_blocks("guide/surfaces.md")[1]),
        *(("guide/thermal.md", block) for block in _python_blocks("guide/thermal.md")),
        *(("guide/plasticity.md", block) for block in _python_blocks("guide/plasticity.md")),
    ]
    monkeypatch.chdir(tmp_path)  # the writer's file goes here
    monkeypatch.setattr(logs, "_handler", logging.NullHandler())
    level, propagate = logs.logger.level, logs.logger.propagate
    namespace: dict = {}
    try:
        for page, block in order:
            exec(compile(block, str(DOCS / page), "exec"), namespace)
    finally:
        logs.logger.setLevel(level)
        logs.logger.propagate = propagate
    import dolfinx_ntf as ntf

    # Quick start: the block carries the load of 10 on the 0.4 x 0.4 punch.
    force = ntf.contact_force(namespace["problem"], "punch")
    assert force[2] == pytest.approx(10.0 * 0.4 * 0.4, rel=1e-8)
    # Modes: the springs carry the punch, which floats without them (docs/guide/modes.md).
    frequencies, floating = namespace["modes"].frequencies, namespace["floating"].frequencies
    assert np.all(np.diff(frequencies) >= 0) and frequencies[0] > 0
    assert abs(floating[0]) < 1e-3 * frequencies[0]
    # Modal dynamics: 100 increments of 1e-5 from rest under the step load, towards -z.
    dynamics = namespace["dynamics"]
    assert dynamics.time == pytest.approx(1e-3) and np.all(np.isfinite(dynamics.q))
    u_dyn = namespace["u_dyn"]
    assert MPI.COMM_WORLD.allreduce(u_dyn.x.array[2::3].min(), op=MPI.MIN) < 0.0
    # Prescribed displacement and outputs: the reactions balance the contact force.
    problem2 = namespace["problem2"]
    top = ntf.reaction(problem2, dofs=namespace["top_bc"])
    assert top[2] == pytest.approx(-ntf.contact_force(problem2)[2], rel=1e-8)
    assert (tmp_path / "punch.xdmf").exists()
    # Friction: never beyond mu = 0.5 of the pressure.
    res3 = namespace["res3"]
    shear = np.linalg.norm(res3.shear, axis=1)
    assert np.all(shear <= 0.5 * np.maximum(res3.pressure, 0) * (1 + 1e-10))
    # Dynamics: four fixed increments.
    assert [r.increment for r in namespace["dynamic_results"]] == [1, 2, 3, 4]
    # SNES: the quick start's solution again (the same load, the same pairs).
    u, u5 = namespace["u"], namespace["u5"]
    assert [r.time for r in namespace["snes_results"]] == [0.5, 1.0]
    assert np.abs(u5.x.array - u.x.array).max() <= 1e-8 * np.abs(u.x.array).max()
    # Thermal contact: the staggered passes converge, the coupled Newton too; heat flows down.
    assert namespace["passes"] <= 10
    assert namespace["norms"][-1] <= 1e-10 * namespace["norms"][0]
    flow = MPI.COMM_WORLD.allreduce(sum(float(q.sum()) for q in namespace["flows"]))
    assert flow > 0.0  # into the slave (the punch): the heated block is the master
    # Plasticity: the punch yielded, the unloading kept the plastic strains, the force is the load.
    material = namespace["material"]
    assert MPI.COMM_WORLD.allreduce(namespace["alpha_loaded"].max(initial=0.0), op=MPI.MAX) > 0
    assert np.array_equal(material.equivalent_plastic_strain, namespace["alpha_loaded"])
    assert namespace["force_pl"][2] == pytest.approx(2.0 * 0.4 * 0.4, rel=1e-8)
    # The gmsh builder of one's own: 3D groups are cell tags, 2D groups facet tags.
    _, cells, facets = mesh_from_gmsh(namespace["build_two_boxes"], MPI.COMM_SELF, size=0.2)
    assert set(np.unique(cells.values)) == {1, 2} and set(np.unique(facets.values)) == {11, 12}
    # Prisms beside hexahedra: one mesh of hexahedra, the prisms' triangles tagged (§32).
    mesh, cells, facets = mesh_from_gmsh(namespace["build_prism_punch"], MPI.COMM_SELF)
    assert mesh.topology.cell_type.name == "hexahedron"
    assert set(np.unique(cells.values)) == {1, 2} and set(np.unique(facets.values)) == {11, 12}


def test_continuum_example_runs(tmp_path, monkeypatch):
    """The guide's Nitsche script runs alone and gives Hertz's approach for its force."""
    monkeypatch.chdir(tmp_path)
    (block,) = _python_blocks("guide/continuum.md")
    namespace: dict = {}
    exec(compile(block, str(DOCS / "guide/continuum.md"), "exec"), namespace)
    # Hertz: the approach a^2/R equals the prescribed 0.3 mm up to the hemisphere's own
    # compliance and the coarse mesh (measured 0.322 mm).
    approach = namespace["a"] ** 2 / namespace["R"]
    assert 0.27 < approach < 0.36


#: Scripts a newcomer wrote from the site's pages alone (the guide's Nitsche script above is the
#: third): each asserts its own checks and prints its numbers.
SITE_SCRIPTS = ROOT / "tests" / "data" / "site"


def _run_site_script(name: str, tmp_path: Path) -> str:
    run = subprocess.run(
        [sys.executable, str(SITE_SCRIPTS / name)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "checks passed" in run.stdout
    return run.stdout


def test_half_cylinder_script_from_the_site(tmp_path):
    """Plane-strain line contact: equilibrium, and Hertz's half-width and peak pressure."""
    out = _run_site_script("half_cylinder_on_block.py", tmp_path)
    forces = [float(f) for f in re.findall(r"(?:contact force|top|base) ([-\d.e+]+) N", out)]
    assert len(forces) == 3 and max(forces) - min(forces) < 1e-8 * max(forces)
    b = float(re.search(r"b = ([\d.]+) mm, p0", out).group(1))
    closed, first_open = map(float, re.search(r"\|x\| = ([\d.]+) mm.*at ([\d.]+) mm", out).groups())
    assert closed - (first_open - closed) < b < first_open  # the edge to one node spacing
    b_error, p0_error = map(float, re.search(r"\(([-+\d.]+)%\).*\(([-+\d.]+)%\)", out).groups())
    # measured -0.5 % and +1.7 % on the script's mesh (0.2 mm at the contact, b = 1.26 mm)
    assert abs(b_error) < 5 and abs(p0_error) < 5


def test_press_and_slide_script_from_the_site(tmp_path):
    """Coulomb friction: the tangential force rises in stick, then stays at mu times the normal."""
    out = _run_site_script("press_and_slide.py", tmp_path)
    rows = re.findall(r"^\s+([\d.]+)\s+(-?[\d.]+)\s+([\d.]+)\s+([\d.]+)\s+(\d+)$", out, re.M)
    ratios = [float(row[3]) for row in rows]
    sliding = [int(row[4]) for row in rows]
    springs = int(re.search(r"(\d+) springs", out).group(1))
    assert len(rows) == 10
    assert ratios[0] < 0.2 and sliding[0] == 0  # the first drag increment sticks
    assert all(a <= b + 1e-4 for a, b in itertools.pairwise(ratios))  # it only grows towards mu
    assert ratios[-1] == pytest.approx(0.3, rel=1e-3) and sliding[-1] == springs
