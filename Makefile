# The two commands of the README: `make demo` and `make test`.
# `make test` checks formatting and lint (ruff), runs the suite on this machine's Debian, then (as root)
# on the other supported Debian release(s) in chroots made and cached by scripts/other_release.sh;
# `make test-here` runs this machine's suite only.
PY := .venv/bin/python
MPIRUN := mpirun --allow-run-as-root --oversubscribe -n 2
MPIRUN3 := mpirun --allow-run-as-root --oversubscribe -n 3
RUFF_VERSION := 0.17.6

.PHONY: setup demo lint test test-here test-other benchmark benchmark-ccx ccx-suite
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

test: lint test-here test-other

test-here: setup
	@echo "== dolfinx_ntf tests on $$(. /etc/os-release && echo "$$PRETTY_NAME"), dolfinx $$($(PY) -c 'import dolfinx; print(dolfinx.__version__)')"
	$(PY) -m pytest -q tests
	$(MPIRUN) $(PY) -m pytest -q -m mpi tests
	$(MPIRUN3) $(PY) -m pytest -q -m mpi tests/test_parallel.py tests/test_parallel_friction.py tests/test_parallel_adjust.py tests/test_parallel_rigid.py tests/test_constraints_mpi.py tests/test_collective.py tests/test_parallel_deck.py

# The other releases in cached chroots: bookworm, trixie and sid by default (the machine's own left
# out); `make test-other RELEASES=sid` (or "trixie sid"...) picks some.
RELEASES ?=
test-other:
	bash scripts/other_release.sh $(RELEASES) test-here

benchmark: setup
	$(PY) benchmarks/contact_phases.py

# dolfinx_ntf against ccx 2.20 on the same decks; writes docs/performance.md (about 15 minutes).
benchmark-ccx: setup
	$(PY) benchmarks/vs_ccx.py

# ccx 2.20 against dolfinx-ntf run on every node-to-surface deck of CalculiX's test suite (a table).
ccx-suite: setup
	$(PY) benchmarks/ccx_suite.py
