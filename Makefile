# Two entry points for a fresh machine with Python 3.11 and pip: `make demo`, `make test`.
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test test-mpi fuzz bench bench-targets report docs venv clean conformance

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "$(PYTHON) not found; run 'make PYTHON=python3 ...'"; exit 1; }
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,plot]"
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	$(PY) examples/fibre_cube_demo.py --out results/demo

test: $(STAMP)
	$(PY) -m pytest -q

# the distributed tests (tests/test_distributed.py) under mpiexec with 1, 2 and 3 ranks; needs the mpi
# extra built against the machine's PETSc and MPI (docs/distributed.md). Open MPI refuses to start as
# root unless both variables are set (containers and CI run as root); --oversubscribe lets 3 ranks
# share 2 cores (MPICH: make test-mpi MPIEXEC_FLAGS=). One Numba thread per rank.
MPIEXEC       ?= mpiexec
MPIEXEC_FLAGS ?= --oversubscribe
MPI_RANKS     ?= 1 2 3
test-mpi: $(STAMP)
	@$(PY) -c "import mpi4py, petsc4py, pymetis" || { echo "make test-mpi: the mpi extra is not installed (docs/distributed.md)"; exit 1; }
	@for n in $(MPI_RANKS); do \
	  echo "== mpiexec -n $$n"; \
	  OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 NUMBA_NUM_THREADS=1 \
	    $(MPIEXEC) $(MPIEXEC_FLAGS) -n $$n $(PY) -m pytest -q -p no:randomly -p no:cacheprovider tests/test_distributed.py \
	    || exit 1; \
	done

# long property-based run of tests/test_fuzz.py and the fuzzed scene files of tests/test_bad_input.py
# (make test runs their bounded, derandomized profile)
fuzz: $(STAMP)
	MORTAR1D3D_HYPOTHESIS=fuzz $(PY) -m pytest tests/test_fuzz.py tests/test_bad_input.py -k "fuzz" -q -p no:randomly --hypothesis-show-statistics

bench: $(STAMP)
	NUMBA_NUM_THREADS=2 $(PY) -m pytest benchmarks -q -p no:randomly -p no:xdist --benchmark-only --benchmark-columns=min,median,max,rounds

# every speed target of issue 22 with its figure and ratio (benchmarks/targets.py): ~40 min;
# QUICK=1 about a third of it, LARGE=1 adds the 1M-unknown solve and 1e7 points (~30 min, 11 GB)
bench-targets: $(STAMP)
	NUMBA_NUM_THREADS=2 $(PY) benchmarks/targets.py $(if $(QUICK),--quick,) $(if $(LARGE),--large,)

# the documentation site: HTML in docs/_build/html, warnings are errors, then every internal link
# and anchor of the built pages and every public name's API entry are checked (docs/check_site.py)
DOCS_STAMP := $(VENV)/.installed-docs
$(DOCS_STAMP): $(STAMP)
	$(PY) -m pip install --quiet -e ".[test,plot,docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	rm -rf docs/_build/html
	$(PY) -m sphinx -b html -W --keep-going -q docs docs/_build/html
	$(PY) docs/check_site.py docs/_build/html

# accuracy-vs-time study (issue 5): report/accuracy_vs_time.md + plots; QUICK=1 for the short run
report: $(STAMP)
	$(PY) -m mortar1d3d.cli bench report --out report $(if $(QUICK),--quick,)

# every 4C input file of $$MORTAR1D3D_4C_INPUTS (else the folder shared/4c-inputs beside the repository's folder): run, compare with its
# RESULT DESCRIPTION, regenerate docs/conformance.md (docs/fourc.md)
conformance: $(STAMP)
	$(PY) benchmarks/conformance.py

clean:
	rm -rf $(VENV) results .pytest_cache .benchmarks docs/_build
	find . -name __pycache__ -type d -prune -exec rm -rf {} +
