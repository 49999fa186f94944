#!/usr/bin/env bash
# Error against run time studies (not tests): CSV and PNG in benchmarks/results/.
# Our FMU alone (pendulum_precision.py), then the peer comparisons with Exudyn
# (peer_*.py, Exudyn from benchmarks/requirements.txt; the rigid + flexible ones
# of issue 5 after the flexible ones) and the wall time at matched error
# (peer_summary.py -> peer_summary.csv); then the per-step cost studies
# (C++ drivers); then the linux64 binary against a pre-portability build of
# the same source (platform_speed.py, which builds that binary first). Run
# times: benchmarks/README.md, "How to run".
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
.venv/bin/python -m pip install -q -r benchmarks/requirements.txt
out=benchmarks/results
.venv/bin/python benchmarks/pendulum_precision.py --out "$out"
for study in peer_r1_pendulum peer_f1_end_moment peer_f3_vibration peer_f4_spin_up \
             peer_f4_motor peer_f5_slider_crank peer_f6_four_bar peer_tip_mass; do
  .venv/bin/python "benchmarks/$study.py" --out "$out"
done
# Rigid reference problems R2-R6 (issue 3).
for study in peer_r2_double_pendulum peer_r3_n_four_bar peer_r4_bricard peer_r5_slider_crank \
             peer_r6_flyball_governor; do
  .venv/bin/python "benchmarks/$study.py" --out "$out"
done
.venv/bin/python benchmarks/peer_summary.py --out "$out"
# Error reached against the FMI tolerance (R1, R2, R4, R5, F3, F4, F5).
.venv/bin/python benchmarks/tolerance_proportionality.py --out "$out"
# Per-step cost of the flexible mesh against element count (C++ driver, built here),
# alone and with rigid bodies attached.
.venv/bin/python benchmarks/flexible_cost.py --out "$out"
.venv/bin/python benchmarks/coupled_cost.py --phases --out "$out"
# Per-step cost of a rigid pendulum chain against the number of bodies (C++ driver, built here),
# then the same chain through the FMU beside Exudyn's KinematicTree.
.venv/bin/python benchmarks/chain_cost.py --out "$out"
.venv/bin/python benchmarks/peer_chain_cost.py --out "$out"
# Co-simulation: closed-loop coupling error against the communication step for
# four masters (zero-order hold Jacobi and Gauss-Seidel, interpolation, rollback).
.venv/bin/python benchmarks/cosim_coupling.py --out "$out"
# Portable linux64 binary against one built the pre-portability way (issue 19):
# instructions in fmi2DoStep (callgrind) and interleaved CPU times. The "before"
# binary links Debian's shared KLU (libsuitesparse-dev, installed here only).
if ! dpkg-query -W -f='${Status}' libsuitesparse-dev 2>/dev/null | grep -q "install ok installed"; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends libsuitesparse-dev >/dev/null
fi
.venv/bin/python benchmarks/platform_speed.py --out "$out"
