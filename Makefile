# The two commands of the README: `make demo` and `make test`.
PY := .venv/bin/python

.PHONY: setup demo test benchmark benchmark-ccx
setup:
	bash scripts/setup.sh

demo: setup
	$(PY) demos/punch.py

test: setup
	$(PY) -m pytest -q tests
	mpirun --allow-run-as-root --oversubscribe -n 2 $(PY) -m pytest -q -m mpi tests

benchmark: setup
	$(PY) benchmarks/contact_phases.py

# dolfinx_ntf against ccx 2.20 on the same decks; writes docs/performance.md (about 15 minutes).
benchmark-ccx: setup
	$(PY) benchmarks/vs_ccx.py
