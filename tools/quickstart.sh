#!/usr/bin/env bash
# hapticd quick start for a fresh Debian 12 machine. Idempotent: installs only the Debian
# packages that are missing (as root, or through sudo), (re)builds incrementally, then
#   tools/quickstart.sh demo   runs `hapticd run` on the embedded config/sim.yaml
#   tools/quickstart.sh test   runs every test, what .ci/run does (stages below)
#   tools/quickstart.sh build  builds the daemon only (what tools/hapticd-plot calls)
# The test command's stages, each timed, all run even when one fails:
#   main    Release build (warnings are errors) and the whole suite, the kernel tests in the
#           kernel test machine included (HAPTICD_KERNEL_TESTS=0 skips those, and says so)
#   asan    one clang build under AddressSanitizer + UndefinedBehaviorSanitizer with the
#           libFuzzer targets: the suite (kernel tests aside), every fuzz target's corpus and
#           regressions replayed, a few seconds of fuzzing each (HAPTICD_FUZZ=0 leaves the
#           fuzz targets out, and says so)
#   tsan    the loop, telemetry and service tests under ThreadSanitizer (sim device only)
# HAPTICD_STAGES="main asan" runs only the named stages.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config   # toolchain
  libyaml-cpp-dev libspdlog-dev libeigen3-dev nlohmann-json3-dev libcli11-dev zlib1g-dev
  libsystemd-dev systemd man-db file             # sd_notify; the unit and man page checked
  libhidapi-dev libusb-1.0-0-dev libgpiod-dev    # the hardware transports
  libgtest-dev libgmock-dev libbenchmark-dev     # tests and benchmarks
  rt-tests python3 util-linux                    # cyclictest and tools/jitter_bench.py; prlimit
  python3-matplotlib                             # tools/hapticd-plot
  libsdp-dev                                     # CSDP: hapticd design-coupling's SDP solver
  qemu-system-x86 busybox-static cpio kmod xz-utils  # tools/kernel-vm, the kernel test machine
  clang libclang-rt-14-dev llvm                  # the asan stage: libFuzzer, llvm-symbolizer
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "quickstart: installing ${missing[*]}"
  as_root=()
  if [[ $(id -u) -ne 0 ]]; then
    if ! command -v sudo >/dev/null; then
      echo "quickstart: installing Debian packages needs root, and sudo is not installed." >&2
      echo "quickstart: run this as root, or install sudo, or install yourself: ${missing[*]}" >&2
      exit 2
    fi
    as_root=(sudo)
  fi
  "${as_root[@]}" apt-get update -q
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# configure_and_build DIR CMAKE_ARGS... [-- TARGETS...]
configure_and_build() {
  local dir=$1 args=() targets=()
  shift
  while (($#)) && [[ $1 != -- ]]; do args+=("$1"); shift; done
  (($#)) && shift && targets=("$@")
  [[ -f $dir/CMakeCache.txt ]] || cmake -S . -B "$dir" -G Ninja -DHAPTICD_WERROR=ON "${args[@]}"
  cmake --build "$dir" ${targets[@]+--target "${targets[@]}"}
}

case "${1:-}" in
  demo)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release
    echo "quickstart: the daemon is build/src/service/hapticd; running the 3 s demo"
    exec build/src/service/hapticd run --duration 3 --log build/demo.hlog ;;
  build)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -- hapticd
    exit 0 ;;
  test) ;;
  *)
    echo "usage: tools/quickstart.sh demo|test|build" >&2
    exit 2 ;;
esac

stages=${HAPTICD_STAGES:-main asan tsan}
failed=()
report=()
run_stage() {
  local name=$1 start=$SECONDS status=0
  shift
  [[ " $stages " == *" $name "* ]] || return 0
  echo "quickstart: === stage $name ==="
  ("$@") || status=$?
  report+=("$(printf '%-5s %4d s  %s' "$name" $((SECONDS - start)) \
    "$([[ $status -eq 0 ]] && echo ok || echo "FAILED ($status)")")")
  [[ $status -eq 0 ]] || failed+=("$name")
}

stage_main() {
  configure_and_build build -DCMAKE_BUILD_TYPE=Release
  cd build && ctest --output-on-failure -j "$(nproc)"
}
# clang, because libFuzzer ships with it: one instrumented build serves both the suite under
# the sanitizers and the fuzz targets (fuzz/README.md), where two builds of the same code
# took a third of the test command. Line tables are all a sanitizer's report needs (full
# debug information: 6 % more compile time, objects 6 times larger, e.g. sim/plant.cpp).
stage_asan() {
  local fuzz=ON
  if [[ ${HAPTICD_FUZZ:-1} == 0 ]]; then
    echo "quickstart: HAPTICD_FUZZ=0: fuzz targets skipped on purpose"
    fuzz=OFF
  fi
  CC=clang CXX=clang++ configure_and_build build-asan-clang -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" \
    -DHAPTICD_SANITIZE=address -DHAPTICD_FUZZ=$fuzz -DHAPTICD_BUILD_BENCHMARKS=OFF \
    -DHAPTICD_BUILD_KERNEL_TESTS=OFF
  # One boot of the kernel test machine per run: the main stage's; its binaries are not even
  # built here (a sixth of the build).
  cd build-asan-clang && ctest --output-on-failure -j "$(nproc)"
}
# Without the CAN, GPIO and HID drivers: the loop, telemetry and service tests run the sim
# device, so those drivers' threads are not exercised here (their own tests run in main and
# asan), and leaving them out takes a fifth of this stage's build (141 steps to 111).
stage_tsan() {
  configure_and_build build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DHAPTICD_SANITIZE=thread \
    -DHAPTICD_BUILD_BENCHMARKS=OFF -DHAPTICD_WITH_CAN=OFF -DHAPTICD_WITH_GPIO=OFF \
    -DHAPTICD_WITH_HID=OFF \
    -- hapticd hapticd_loop_tests hapticd_telemetry_tests hapticd_service_tests \
    hapticd_service_unit_tests
  # Not the random-signal trial: TSan intercepts signals and defers them to its own safe
  # points, and one trial in three loaded runs lost a start-up signal that way (never in the
  # main or asan stage, which run it too). This stage is for data races.
  cd build-tsan && ctest --output-on-failure -j "$(nproc)" -L "^(loop|telemetry|service)$" \
    -E "^FaultInjection.RandomSignalsAtRandomMomentsAlwaysEndSafely$"
}

run_stage main stage_main
run_stage asan stage_asan
run_stage tsan stage_tsan
echo "quickstart: stage  time    result"
printf 'quickstart: %s\n' "${report[@]}"
if ((${#failed[@]})); then
  echo "quickstart: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "quickstart: every stage passed"
