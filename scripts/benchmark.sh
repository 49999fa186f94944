#!/usr/bin/env bash
# Error against run time studies (not tests): CSV and PNG in benchmarks/results/.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
.venv/bin/python benchmarks/pendulum_precision.py --out benchmarks/results
