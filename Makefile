# Set-up commands from the README: `make demo` and `make test` work on a fresh clone.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
BUILD_DEPS := "scikit-build-core>=0.10" "nanobind>=2.4" "cmeel-eigen>=3.4"

.PHONY: demo test lint build bench clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip

# Editable install without build isolation (see shared BUILD-NOTES): the build
# requirements live in .venv, the C++ core rebuilds on import when sources change.
# GenZ-LIO is then rebuilt from its sdist with lf3pm's patch (third_party/genz_lio).
$(STAMP): $(PY) pyproject.toml CMakeLists.txt third_party/genz_lio/init_pose_variance.patch third_party/genz_lio/build.sh
	$(PY) -m pip install -q $(BUILD_DEPS)
	$(PY) -m pip install -q --no-build-isolation -Ceditable.rebuild=true -e ".[test,lio,cluster]"
	third_party/genz_lio/build.sh $(PY) build/genz_lio
	touch $(STAMP)

build: $(STAMP)

demo: build
	$(PY) -m lf3pm.demo --out out

# ruff (lint and format, pyproject.toml) on the Python, clang-format (.clang-format) on the C++.
lint: build
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/clang-format --dry-run --Werror $$(find cpp -name '*.[ch]pp')

# The browser test of `lf3pm view` needs Debian's chromium: installed here when we may
# (as root), else that one test is skipped with its reason.
test: lint
	@command -v chromium >/dev/null 2>&1 || { [ "$$(id -u)" = 0 ] && { apt-get install -y -q chromium >/dev/null 2>&1 \
	  || { apt-get update -q >/dev/null 2>&1 && apt-get install -y -q chromium >/dev/null 2>&1; }; }; } \
	  || echo "chromium not installed: the browser test of lf3pm view will be skipped"
	$(PY) -m pytest -q

# Every benchmark in bench/, each printing its ratio against its baseline (tests/test_bench.py
# checks that each script is listed here). bench_evaluate.py's Embree baseline needs embreex.
# The SOLM benchmark's baseline uses Open3D, whose import needs Debian's
# libusb-1.0-0 (shared BUILD-NOTES): installed here when we may, else said why not.
bench: build
	$(PY) -m pip install -q "open3d>=0.18" embreex
	@$(PY) -c "import open3d" 2>/dev/null || { [ "$$(id -u)" = 0 ] && apt-get install -y -q libusb-1.0-0 >/dev/null; } \
	  || { echo "open3d cannot load: install Debian's libusb-1.0-0 (as root) for bench/bench_solm.py"; exit 1; }
	$(PY) bench/bench_builds.py
	$(PY) bench/bench_evaluate.py
	$(PY) bench/bench_audit.py
	$(PY) bench/bench_solm.py
	$(PY) bench/bench_solm_yaw_reuse.py
	$(PY) bench/bench_solm_approximations.py
	$(PY) bench/bench_flight_solm.py --full
	$(PY) bench/bench_site_floor.py
	$(PY) bench/bench_graph_search.py
	$(PY) bench/bench_esdf.py
	$(PY) bench/bench_planner_backend.py
	$(PY) bench/bench_flight_replan.py
	$(PY) bench/bench_planner_occupancy.py
	for robot in omni diff car; do $(PY) bench/bench_random_queries.py --robot $$robot || exit 1; done
	$(PY) bench/bench_motion.py
	$(PY) bench/bench_odometry_replay.py
	$(PY) bench/bench_replay.py
	$(PY) bench/bench_solm_cluster.py
	$(PY) bench/bench_solm_memory.py

clean:
	rm -rf build out $(VENV)
