#!/usr/bin/env bash
# hapticd quick start for a fresh Debian 12 machine. Idempotent: installs only the Debian
# packages that are missing, (re)builds incrementally, then
#   tools/quickstart.sh demo   runs `hapticd run` on the embedded config/sim.yaml
#   tools/quickstart.sh test   runs the whole test suite (what .ci/run does)
# HAPTICD_SANITIZE=1 builds the test run with ASan+UBSan in build-asan/.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  build-essential cmake ninja-build pkg-config   # toolchain
  libyaml-cpp-dev libspdlog-dev libeigen3-dev nlohmann-json3-dev libcli11-dev zlib1g-dev
  libsystemd-dev systemd                         # sd_notify; systemd-analyze checks the unit
  libhidapi-dev libusb-1.0-0-dev libgpiod-dev    # the hardware transports
  libgtest-dev libgmock-dev libbenchmark-dev     # tests and benchmarks
  rt-tests python3 util-linux                    # cyclictest and tools/jitter_bench.py; prlimit
  qemu-system-x86 busybox-static cpio kmod xz-utils  # tools/kernel-vm, the kernel test machine
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "quickstart: installing ${missing[*]}"
  sudo=""
  [[ $(id -u) -ne 0 ]] && sudo=sudo
  $sudo apt-get update -q
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

build=build
cmake_args=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo)
if [[ ${HAPTICD_SANITIZE:-0} == 1 ]]; then
  build=build-asan
  cmake_args+=(-DHAPTICD_SANITIZE=ON -DHAPTICD_BUILD_BENCHMARKS=OFF)
fi
[[ -f $build/CMakeCache.txt ]] || cmake -S . -B "$build" "${cmake_args[@]}"
cmake --build "$build"

case "${1:-}" in
  demo)
    exec "$build/src/service/hapticd" run --duration 3 --log "$build/demo.hlog" ;;
  test)
    # --- fuzz step (fuzz/README.md): clang build in build-fuzz/, every fuzz regression
    # replayed, then 5 s of fuzzing per target; HAPTICD_FUZZ=0 skips it. ---
    fuzz_status=0
    [[ ${HAPTICD_FUZZ:-1} == 0 ]] || tools/fuzz.sh test || fuzz_status=$?
    # --- end fuzz step ---
    cd "$build" && ctest --output-on-failure -j "$(nproc)"
    exit "$fuzz_status" ;;
  *)
    echo "usage: tools/quickstart.sh demo|test" >&2
    exit 2 ;;
esac
