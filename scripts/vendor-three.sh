#!/usr/bin/env bash
# Copy three.js (the version tests/clients/js/package.json pins) into the package's viewer assets
# (runtime/view/assets/three/): run after changing the pinned version, with THREE_VERSION in
# runtime/view/assets.py updated to match. tests/clients/test_view.py fails when the copies differ.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-python}"
[ -f tests/clients/js/node_modules/three/package.json ] || (cd tests/clients/js && npm ci --no-audit --no-fund --loglevel=error)
"$PYTHON" -m cgaskin.view.assets tests/clients/js/node_modules/three
