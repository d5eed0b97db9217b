#!/usr/bin/env bash
# Build cgaskin's documentation site into docs/_build/html: offline (no intersphinx, MathJax from the
# site itself), every gallery example run for its pictures, numpydoc validation on, warnings as errors.
#
#   pip install -e '.[docs]' && bash scripts/build-docs.sh
#
# Installs nothing. Switches (environment): CGASKIN_DOCS_VALIDATE=0 (docstring checks off, while they
# are pending), CGASKIN_DOCS_GALLERY=0 (gallery pages without running the examples), CGASKIN_DOCS_CLEAN=1
# (forget the gallery's earlier outputs: every example runs again; a clone has none anyway).
# The docstrings that fail validation are listed in docs/_build/docstring-validation.txt.
set -euo pipefail
cd "$(dirname "$0")/.."

python - <<'PY'
import importlib.util, sys
missing = [m for m in ("sphinx", "pydata_sphinx_theme", "numpydoc", "sphinx_gallery", "matplotlib", "cgaskin")
           if importlib.util.find_spec(m) is None]
if missing:
    sys.exit(f"build-docs: {', '.join(missing)} missing: pip install -e '.[docs]'")
PY

if [ "${CGASKIN_DOCS_CLEAN:-0}" = 1 ]; then
    rm -rf docs/_build docs/auto_examples docs/_pages docs/api/generated
fi
start=$(date +%s)
# -E: read every page again, so that every warning (a docstring's too) is reported on every build;
# the gallery still reruns only the examples whose source changed since their pictures were made
status=0
python -m sphinx -b html -E -W --keep-going docs docs/_build/html || status=$?
echo "build-docs: $(( $(date +%s) - start )) s; site: docs/_build/html/index.html"
if [ -s docs/_build/docstring-validation.txt ] && [ "$(grep -vc '^#' docs/_build/docstring-validation.txt)" != 0 ]; then
    echo "build-docs: docstrings failing numpydoc validation: docs/_build/docstring-validation.txt"
fi
exit $status
