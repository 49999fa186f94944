#!/usr/bin/env bash
# A long run of the FMI fuzz test (tests/python/fmi_fuzz.py): random call
# sequences over every example FMU, each FMU's in a child process. Prints
# the seed; each violation comes with the command that replays it.
#   bash scripts/fuzz.sh [SECONDS_PER_FMU] [SEED]      (default 300 s, a random seed)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
seed=()
if [ $# -ge 2 ]; then seed=(--seed "$2"); fi
exec .venv/bin/python tests/python/fmi_fuzz.py --budget "${1:-300}" "${seed[@]}"
