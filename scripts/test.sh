#!/usr/bin/env bash
# Set up (virtualenv + every dependency) and run the whole test suite and the linter.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[all]"
.venv/bin/python -m ruff check src tests benchmarks
.venv/bin/python -m pytest
