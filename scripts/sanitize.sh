#!/usr/bin/env bash
# AddressSanitizer and UndefinedBehaviorSanitizer: a build of their own
# (build-asan/), the C++ unit tests, instantiate/run/free cycles of an FMU
# built there (with leak checking), and the quick FMI fuzz run against that
# build's FMUs. Exits non-zero on the first report.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root"
flags="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
# No link-time optimisation (it multiplies the build time; nothing to check
# in it), no win64 build, and the system's shared libstdc++: a static one
# in the FMU leaves its emergency exception pool (one 72,704-byte block per
# load) behind when the FMU is unloaded, which LeakSanitizer reports.
# C++ only is instrumented: KLU's C sources are third-party code.
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "${launcher[@]}" \
  -DMFBD_LTO=OFF -DMFBD_WIN64=OFF -DMFBD_PORTABLE_LINUX64=OFF \
  -DPython3_EXECUTABLE="$root/.venv/bin/python" \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" \
  -DCMAKE_SHARED_LINKER_FLAGS="$flags" -DCMAKE_MODULE_LINKER_FLAGS="$flags" >/dev/null
cmake --build build-asan -j "$(nproc)"

export ASAN_OPTIONS="abort_on_error=0:halt_on_error=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
ctest --test-dir build-asan --output-on-failure

# An FMU of this build, loaded by a sanitized harness: 50 cycles, leaks checked.
fmu=build-asan/fmus/pendulum.fmu
unzip=$(mktemp -d)
trap 'rm -rf "$unzip"' EXIT
.venv/bin/python -c "import zipfile, sys; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])" "$fmu" "$unzip"
guid=$(sed -n 's/.* guid="\([^"]*\)".*/\1/p' "$unzip/modelDescription.xml" | head -1)
build-asan/tests/cpp/fmu_instance_cycles "$unzip/binaries/linux64/pendulum.so" "file://$unzip/resources" "$guid" 50

# The fuzz test against this build's FMUs, in Python: the sanitizer runtimes
# preloaded (Python itself is not instrumented: its leaks are not checked).
preload="$(g++ -print-file-name=libasan.so):$(g++ -print-file-name=libubsan.so)"
# Instrumented, a sequence runs about 20x slower (motor_spin_up seed 15,
# sequence 19: 63 s against 2.9 s): a longer wait before calling it a hang.
ASAN_OPTIONS="$ASAN_OPTIONS:detect_leaks=0" LD_PRELOAD="$preload" MFBD_BUILD="$root/build-asan" MFBD_FUZZ_HANG_SECONDS=600 \
  .venv/bin/python -m pytest tests/python/test_fmi_fuzz.py tests/python/test_fmi_robustness.py -q -p no:cacheprovider
