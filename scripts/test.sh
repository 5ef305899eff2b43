#!/usr/bin/env bash
# Set up (virtualenv + every dependency) and run the whole test suite and the linter.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[all]"
# the editable install leaves the sources uncompiled, and with PYTHONDONTWRITEBYTECODE set every
# process the tests start would compile kinprop's ~90 modules again (~0.25 s of CPU each time)
.venv/bin/python -m compileall -q src
.venv/bin/python -m ruff check src tests benchmarks
.venv/bin/python -m ruff format --check src tests benchmarks
scripts/install-test-deps.sh || echo "warning: chromium not installed: the browser test fails when CI is set, else skips" >&2
.venv/bin/python -m pytest
