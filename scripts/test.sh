#!/usr/bin/env bash
# Every test: C++ unit tests (ctest) and the FMU tests through fmpy, libcosim
# and valgrind (pytest). Exits non-zero if any fails.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
status=0
ctest --test-dir build --output-on-failure || status=1
.venv/bin/python -m pytest tests/python -q || status=1
exit $status
