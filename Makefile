# Set-up commands from the README: `make demo` and `make test` work on a fresh clone.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
BUILD_DEPS := "scikit-build-core>=0.10" "nanobind>=2.4" "cmeel-eigen>=3.4"

.PHONY: demo test build bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

# Editable install without build isolation (see shared BUILD-NOTES): the build
# requirements live in .venv, the C++ core rebuilds on import when sources change.
$(STAMP): $(PY) pyproject.toml CMakeLists.txt
	$(PY) -m pip install -q $(BUILD_DEPS)
	$(PY) -m pip install -q --no-build-isolation -Ceditable.rebuild=true -e ".[test]"
	touch $(STAMP)

build: $(STAMP)

demo: build
	$(PY) -m lf3pm.demo --out out

test: build
	$(PY) -m pytest -q

bench: build
	$(PY) bench/bench_evaluate.py

clean:
	rm -rf build out $(VENV)
