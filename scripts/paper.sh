#!/usr/bin/env bash
# Set up and run the main job: the paper's two examples, our values beside the paper's.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m venv .venv
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q -e ".[all]"
.venv/bin/kinprop paper
