#!/usr/bin/env bash
# Set up, then run the test suite (fast tests; long campaigns live in ci/) on every core (pytest-xdist: -n auto; give
# -n 0 to run in this process). Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/setup.sh
export HYPOTHESIS_PROFILE="${HYPOTHESIS_PROFILE:-ci}"
python3 -m pytest -n auto "$@"
