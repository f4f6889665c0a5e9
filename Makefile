# bladelab: two commands do all the set-up on a fresh machine (Python 3.11, pip, gcc, make).
#   make demo   installs bladelab into .venv and runs the main job on the embedded example study
#   make test   installs the test dependencies (pytest, pytest-xdist, pytest-timeout, statsmodels,
#               ruff, ray) and runs the tests on two workers
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python

.PHONY: demo test bench lint clean clean-cache

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(VENV)/.installed-base: pyproject.toml | $(VENV)/bin/python
	$(PY) -m pip install --quiet -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(VENV)/bin/python
	$(PY) -m pip install --quiet -e ".[test,ray]"
	touch $@ $(VENV)/.installed-base

demo: $(VENV)/.installed-base
	$(PY) -m bladelab.demo

# two workers, each test file on one of them (its module fixtures built once): the suite
# took 9-10 min serial on CI's 2 cores
test: $(VENV)/.installed-test
	$(PY) -m pytest -q -n 2 --dist loadfile

bench: $(VENV)/.installed-test
	$(PY) benchmarks/run.py

lint: $(VENV)/.installed-test
	$(VENV)/bin/ruff check src tests benchmarks

clean: clean-cache
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache

# numba's on-disk cache of compiled functions (keyed on each function's own file; bladelab
# flushes it by itself when a compiled source changes: bladelab/numba_cache.py), and the
# compiled collocation node functions (keyed on their graphs: bladelab/predict/collocation/compiled.py)
clean-cache:
	find src -name '*.nbi' -delete -o -name '*.nbc' -delete
	rm -f "$${BLADELAB_CACHE_DIR:-$${XDG_CACHE_HOME:-$$HOME/.cache}/bladelab/casadi}"/node-*.so
