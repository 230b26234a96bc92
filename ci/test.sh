#!/usr/bin/env bash
# Set up, then run the fast tests on every core (pytest-xdist: -n auto; give -n 0 to run in this process) under the
# `dev` hypothesis profile, the ten slowest printed (tests that share a module's costly fixture carry an xdist_group:
# --dist loadgroup runs them on one worker, which builds it once). .ci/run runs the same under the `ci` profile
# (HYPOTHESIS_PROFILE=ci: more examples, whole sweeps) with the `slow` tests in the same session (-m "slow or not slow":
# campaigns, kilometres of drives, every command the docs show). Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash ci/setup.sh
export HYPOTHESIS_PROFILE="${HYPOTHESIS_PROFILE:-dev}"
# bytecode caches (__pycache__, not tracked) spare each of the suite's hundreds of fresh processes compiling the project
# again (0.2 s each) and each worker rewriting the tests' asserts again (6 s): an environment that turns them off does
# not turn them off here
unset PYTHONDONTWRITEBYTECODE
python3 -m pytest -n auto --dist loadgroup --durations=10 "$@"
