#!/usr/bin/env bash
# The Python package's tests: build the extension into a venv (under the cargo target
# directory; created on first use with maturin, numpy, pytest and dask[distributed] from PyPI)
# and run pytest.
#
#   bash python/test.sh [PYTEST_ARGS...]
#
# The extension is built with the release profile, as `pip install ./python` builds it (the
# real-time loop tests need release speed).
# PACS_TEST_LEROBOT=1 also runs the tests against LeRobot's real classes (ACT, diffusion,
# the processor pipeline), installing lerobot 0.6 into the venv if it lacks it (it pulls
# torch: ≈ 5.5 GB; lerobot 0.6 needs Python >= 3.12, so use a venv of its own:
#   PYTHON=python3.12 PACS_PYTHON_VENV=/tmp/pacs-lerobot-venv PACS_TEST_LEROBOT=1 bash python/test.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
target_dir="${CARGO_TARGET_DIR:-target}"
venv="${PACS_PYTHON_VENV:-$target_dir/python-venv}"
python="${PYTHON:-python3}"
if ! "$python" -c 'import sys; assert sys.version_info >= (3, 10)' 2>/dev/null; then
  echo "python/test.sh: needs Python >= 3.10 as \`$python\` (set PYTHON=...)" >&2
  exit 1
fi
if ! "$venv/bin/python" -c 'import maturin, numpy, pytest' 2>/dev/null; then
  rm -rf "$venv"
  "$python" -m venv "$venv"
  "$venv/bin/pip" install -q --upgrade pip
  "$venv/bin/pip" install -q "maturin>=1.9,<2" "numpy>=1.21" "pytest>=7"
fi
# rosbags (an independent writer of ROS 2 bags) for the db3 tests, which skip without it.
if ! "$venv/bin/python" -c 'import rosbags' 2>/dev/null; then
  "$venv/bin/pip" install -q "rosbags>=0.11,<0.12"
fi
# Dask (pacs.fleet on a LocalCluster, python/tests/test_fleet.py): installed into an existing
# venv too.
if ! "$venv/bin/python" -c 'import dask.distributed' 2>/dev/null; then
  "$venv/bin/pip" install -q "dask[distributed]>=2024.8,<2027"
fi
if [ "${PACS_TEST_LEROBOT:-}" = 1 ] && ! "$venv/bin/python" -c 'import lerobot' 2>/dev/null; then
  if ! "$venv/bin/python" -c 'import sys; assert sys.version_info >= (3, 12)' 2>/dev/null; then
    echo "python/test.sh: PACS_TEST_LEROBOT=1 needs lerobot 0.6, which needs Python >= 3.12;" \
      "$venv has $("$venv/bin/python" -V 2>&1) (set PYTHON=python3.12 and PACS_PYTHON_VENV=DIR)" >&2
    exit 1
  fi
  "$venv/bin/pip" install -q "lerobot[diffusion]>=0.6,<0.7"
fi
# maturin develop installs into the active virtualenv.
VIRTUAL_ENV="$(cd "$venv" && pwd)" PATH="$(cd "$venv" && pwd)/bin:$PATH" \
  "$venv/bin/maturin" develop -q --release -m python/Cargo.toml
"$venv/bin/python" -m pytest -q python/tests "$@"
