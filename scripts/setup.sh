#!/usr/bin/env bash
# Set-up shared by every script: Debian packages, a Python venv (.venv), and
# the CMake build (build/). Idempotent: what is already there is kept.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

# libzip and pugixml: the packer writes the FMU zip (deflate) and
# modelDescription.xml with them, on the build host only.
# MinGW-w64 (POSIX threads) cross-compiles the win64 FMU binary; wine runs
# it in the tests (tests/python/test_platforms.py).
packages=(cmake ninja-build g++ make binutils libeigen3-dev nlohmann-json3-dev
          libzip-dev libpugixml-dev
          libgtest-dev valgrind python3 python3-venv
          g++-mingw-w64-x86-64-posix gcc-mingw-w64-x86-64-posix wine wine64)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  echo "setup: installing Debian packages: ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Python venv with the packages of requirements.txt (re-installed when it changes).
python=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
  echo "setup: creating .venv"
  "$python" -m venv .venv
fi
stamp=.venv/.requirements.sha256
want=$(sha256sum requirements.txt | cut -d' ' -f1)
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "setup: installing Python packages (requirements.txt)"
  .venv/bin/python -m pip install -q --upgrade pip
  .venv/bin/python -m pip install -q -r requirements.txt
  echo "$want" > "$stamp"
fi

# Build: solver, FMU binary, packer, tests, one .fmu per example scene.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE="$root/.venv/bin/python" >/dev/null
cmake --build build -j "$(nproc)"
