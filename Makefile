# Two commands on a fresh machine: `make demo` and `make test`. Each creates .venv if missing.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test bench clean

# TrackEval (HOTA) without its declared dependencies: see the comment in pyproject.toml.
TRACKEVAL := trackeval==1.3.0

$(STAMP): pyproject.toml Makefile
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test,baseline]'
	$(PY) -m pip install --quiet --no-deps '$(TRACKEVAL)'
	@echo "compiling the trackers' kernels once (cached in src/**/__pycache__; a few minutes on a small machine)"
	$(PY) -m worldtrack.warmup
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/worldtrack demo

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

clean:
	rm -rf $(VENV) demo_out .pytest_cache
