#!/usr/bin/env bash
# The main job: set up and build, pack every example scene into an .fmu
# (build/fmus/), simulate the default example through fmpy, and write a CSV
# and a PNG plot (out/).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
echo "main: example FMUs:"
ls -1 build/fmus/*.fmu | sed 's/^/  /'
.venv/bin/python examples/simulate.py build/fmus/pendulum.fmu --out out
