#!/bin/sh
# Builds GenZ-LIO 0.1.1 from its sdist with lf3pm's patch (init_pose_variance.patch,
# README.md says why) and installs it into the venv of PYTHON, over PyPI's wheel.
# Usage: third_party/genz_lio/build.sh PYTHON WORKDIR, in a venv that has genz-lio's
# dependencies (make installs the lio extra first). Does nothing when that build
# is already installed (a new patch bumps the version it sets). GPL-2.0-only code, built on
# this machine only.
set -eu
PY=$1
WORK=$(mkdir -p "$2" && cd "$2" && pwd)
HERE=$(cd "$(dirname "$0")" && pwd)
# The version the patch gives the build (lf3pm/replays/lio.py's GENZ_LF3PM_BUILD must match:
# tests/test_lio.py checks the installed build against it).
VERSION=$(sed -n 's/^+version = "\(.*\)"$/\1/p' "$HERE/init_pose_variance.patch")
SDIST_SHA256=03952763ece184160132a0b55891ea77362c17258cd3c1964da91ebed3df6552

if "$PY" -c "import sys; sys.exit(sys.version_info < (3, 13))"; then
  echo "GenZ-LIO needs Python < 3.13: not built (lf3pm's genz odometry says so when asked)"
  exit 0
fi
if "$PY" -c "import genz_lio, sys; sys.exit(genz_lio.__version__ != '$VERSION')" 2>/dev/null; then
  exit 0
fi
command -v patch >/dev/null || { echo "building GenZ-LIO needs patch(1) (Debian: apt-get install patch)" >&2; exit 1; }
echo "building GenZ-LIO $VERSION (GenZ-LIO 0.1.1 with lf3pm's initial-covariance patch; a few minutes)"
rm -rf "$WORK" && mkdir -p "$WORK"
"$PY" -m pip download -q --no-deps --no-binary genz-lio genz-lio==0.1.1 -d "$WORK"
echo "$SDIST_SHA256  $WORK/genz_lio-0.1.1.tar.gz" | sha256sum -c --quiet -
tar xzf "$WORK/genz_lio-0.1.1.tar.gz" -C "$WORK"
patch -s -p1 -d "$WORK/genz_lio-0.1.1" < "$HERE/init_pose_variance.patch"
# Eigen and Boost headers from PyPI (cmeel), in the work folder only.
"$PY" -m pip install -q --no-deps --target "$WORK/deps" cmeel-eigen==3.4.1 cmeel-boost==1.90.0
PREFIX="$WORK/deps/cmeel.prefix"
CMAKE_PREFIX_PATH="$PREFIX" CXXFLAGS="-I$PREFIX/include" CMAKE_BUILD_PARALLEL_LEVEL="${CMAKE_BUILD_PARALLEL_LEVEL:-2}" \
  "$PY" -m pip wheel -q --no-deps -w "$WORK/wheel" "$WORK/genz_lio-0.1.1"
"$PY" -m pip install -q --no-deps --force-reinstall "$WORK"/wheel/genz_lio-*.whl
"$PY" -c "import genz_lio, sys; sys.exit(genz_lio.__version__ != '$VERSION')"
rm -rf "$WORK/deps" "$WORK/genz_lio-0.1.1"
