# The two commands of the README: `make demo` and `make test` (which starts with `make lint`).
PY := .venv/bin/python

.PHONY: setup demo lint test benchmark
setup:
	bash scripts/setup.sh

demo: setup
	$(PY) demos/punch.py

lint: setup
	.venv/bin/ruff format --check .
	.venv/bin/ruff check .

test: lint
	$(PY) -m pytest -q tests
	mpirun --allow-run-as-root --oversubscribe -n 2 $(PY) -m pytest -q -m mpi tests

benchmark: setup
	$(PY) benchmarks/contact_phases.py
