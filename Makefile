# The two commands of the README: `make demo` and `make test`.
# `make test` checks formatting and lint (ruff) and runs the suite on this machine's Debian (serial, then on 2
# and 3 ranks). `make test-all` (what CI runs) adds the documentation site's check and, as root, the suite and
# the site on the other supported Debian releases in chroots made and cached by scripts/other_release.sh.
# `make docs` builds the site, `make docs-check` tests it.
PY := .venv/bin/python
MPIRUN := mpirun --allow-run-as-root --oversubscribe -n 2
MPIRUN3 := mpirun --allow-run-as-root --oversubscribe -n 3
RUFF_VERSION := 0.17.6

.PHONY: setup demo lint docs docs-check test test-all test-here test-other benchmark benchmark-ccx ccx-suite
setup:
	bash scripts/setup.sh

demo: setup
	$(PY) demos/punch.py

lint: setup
	@[ "$$(.venv/bin/ruff --version 2>/dev/null)" = "ruff $(RUFF_VERSION)" ] || \
		$(PY) -m pip install -q "ruff==$(RUFF_VERSION)"
	.venv/bin/ruff format --check .
	.venv/bin/ruff check .
	$(PY) scripts/check_layers.py

# The site: docs/_build/html from docs/ (Sphinx, MyST, furo, sphinx-gallery running the demos on their
# coarse meshes); nitpicky, warnings are errors. docs-check builds it again and opens it in Chromium.
docs: setup
	PYTHONPATH=$(CURDIR) $(PY) -m sphinx -b html -n -W --keep-going -E docs docs/_build/html

docs-check: setup
	PYTHONPATH=$(CURDIR) $(PY) -m pytest -q -p no:cacheprovider -m docs tests/test_docs.py

test: lint test-here

test-all: lint docs-check test-here test-other

test-here: setup
	@start=$$(date +%s); echo "== dolfinx_ntf tests on $$(. /etc/os-release && echo "$$PRETTY_NAME"), dolfinx $$($(PY) -c 'import dolfinx; print(dolfinx.__version__)')"; \
	$(PY) -m pytest -q -m "not docs" tests && \
	$(MPIRUN) $(PY) -m pytest -q -m mpi tests && \
	$(MPIRUN3) $(PY) -m pytest -q -m mpi tests/parallel/test_parallel.py tests/parallel/test_parallel_friction.py tests/parallel/test_parallel_adjust.py tests/parallel/test_parallel_rigid.py tests/parallel/test_constraints_mpi.py tests/parallel/test_collective.py tests/parallel/test_parallel_deck.py tests/solvers/test_snes.py tests/contact/test_contact_axisymmetric.py && \
	echo "test-here: passed in $$(( $$(date +%s) - start )) s"

# The other releases in cached chroots: bookworm, trixie and sid but the machine's own by default;
# `make test-other RELEASES=sid` (or "trixie sid") picks some.
RELEASES ?=
test-other:
	bash scripts/other_release.sh $(RELEASES) test-here docs-check

benchmark: setup
	$(PY) benchmarks/contact_phases.py

# dolfinx_ntf against ccx 2.20 on the same decks; writes docs/performance.md (about 15 minutes).
benchmark-ccx: setup
	$(PY) benchmarks/vs_ccx.py

# ccx 2.20 against dolfinx-ntf run on every node-to-surface deck of CalculiX's test suite (a table).
ccx-suite: setup
	$(PY) benchmarks/ccx_suite.py
