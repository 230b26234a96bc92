#!/usr/bin/env bash
# Set up, then run the test suite (fast tests; long campaigns live in ci/). Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/setup.sh
export HYPOTHESIS_PROFILE="${HYPOTHESIS_PROFILE:-ci}"
python3 -m pytest "$@"
