#!/usr/bin/env bash
# Install what the suite needs: Spin and gcc from Debian when missing, then this package and its
# Python dependencies from PyPI (editable, with the dev tools ruff and mypy) at the versions ci/constraints.txt
# pins. OVERTAKE_BROWSER=1 also installs Debian's chromium, which the report's browser test drives (CI always
# sets it; Playwright never downloads a browser).
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v spin >/dev/null 2>&1 || ! command -v gcc >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  echo "setup: installing spin and gcc with apt-get" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq spin gcc >/dev/null
fi
if [ "${OVERTAKE_BROWSER:-0}" = 1 ] && ! command -v chromium >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" = 0 ] || SUDO="sudo"
  echo "setup: installing chromium with apt-get (OVERTAKE_BROWSER=1)" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq chromium >/dev/null
fi
# Skipped when this checkout is what Python imports and pyproject.toml and ci/constraints.txt are unchanged since this
# checkout's last install (.setup-stamp, not tracked): a contributor's repeated test runs do not pay for pip (15 s).
stamp=".setup-stamp"
want="$(cat pyproject.toml ci/constraints.txt | sha256sum | cut -d' ' -f1) $(command -v python3)"
# (asked from / : from here Python would import this checkout's spec/ whatever the install points at)
here="$(cd / && python3 -c 'import pathlib, spec; print(pathlib.Path(spec.__file__).resolve().parents[1])' 2>/dev/null || true)"
if [ "$here" = "$(pwd -P)" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
python3 -m pip install -q --disable-pip-version-check --root-user-action=ignore -c ci/constraints.txt -e '.[dev]'
echo "$want" > "$stamp"
