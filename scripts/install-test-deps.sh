#!/usr/bin/env bash
# System packages the tests need beyond the Python ones: Debian's chromium, for the headless
# browser test of the interactive HTML plots (tests/plot/test_plots.py). Idempotent.
set -euo pipefail
if command -v chromium >/dev/null 2>&1; then
    exit 0
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then
    SUDO="sudo"
fi
if ! command -v apt-get >/dev/null 2>&1; then
    echo "install-test-deps: no apt-get here; install the 'chromium' browser by hand" >&2
    exit 1
fi
export DEBIAN_FRONTEND=noninteractive  # CI has no terminal: never prompt
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq chromium
command -v chromium >/dev/null
