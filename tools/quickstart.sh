#!/usr/bin/env bash
# hapticd quick start for a fresh Debian 12 (bookworm) or 13 (trixie) machine. Idempotent:
# installs only the Debian packages that are missing (as root, or through sudo), (re)builds
# incrementally, then
#   tools/quickstart.sh demo   builds the daemon and runs `hapticd run` on the embedded
#                              config/sim.yaml (nothing else is built)
#   tools/quickstart.sh test   builds what the stages below need and runs every test once,
#                              what .ci/run does
#   tools/quickstart.sh build  builds the daemon only (what tools/hapticd-plot calls)
#   tools/quickstart.sh packages  installs what test needs and builds nothing (tools/fuzz.sh)
# The test command's stages, each timed, all run even when one fails:
#   main    Release build (warnings are errors) of the daemon, the benchmarks and what these
#           tests run: the kernel tests in the kernel test machine and the service under that
#           machine's systemd (HAPTICD_KERNEL_TESTS=0 skips both boots, and says so), the
#           coupling designs end to end, the plot tool, the layering probes
#   asan    one clang build under AddressSanitizer + UndefinedBehaviorSanitizer with the
#           libFuzzer targets: the rest of the suite, every fuzz target's corpus and
#           regressions replayed, a few seconds of fuzzing each (HAPTICD_FUZZ=0 leaves the
#           fuzz targets out, and says so); built in the background while main runs
#   tsan    the loop, telemetry and service tests under ThreadSanitizer (sim device only)
# HAPTICD_STAGES="main asan" runs only the named stages.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-}
case $mode in
  demo | build | test | packages) ;;
  *)
    echo "usage: tools/quickstart.sh demo|test|build|packages" >&2
    exit 2 ;;
esac

# What configuring and building needs (CMake looks for every library, the test frameworks
# included, when it configures build/, which demo, build and test share).
packages=(
  build-essential cmake ninja-build pkg-config python3  # toolchain; the layering check
  libyaml-cpp-dev libspdlog-dev libeigen3-dev nlohmann-json3-dev libcli11-dev zlib1g-dev
  libsystemd-dev                                        # sd_notify
  libhidapi-dev libusb-1.0-0-dev libgpiod-dev           # the hardware transports
  libevdev-dev                                          # evdev: force feedback through the
                                                        # kernel's input devices
  libgtest-dev libgmock-dev libbenchmark-dev            # tests and benchmarks
  libsdp-dev                                            # CSDP: design-coupling's SDP solver
)
[[ $mode == demo ]] || packages+=(python3-matplotlib)   # tools/hapticd-plot (and its test)
test_packages=(
  systemd man-db file                                   # the unit and man page checked;
                                                        # systemd is PID 1 of tests/systemd's boot
                                                        # (run from /lib/systemd/systemd: no
                                                        # systemd-sysv, dbus or procps needed)
  rt-tests util-linux                                   # cyclictest, jitter_bench.py; prlimit; runuser
  qemu-system-x86 busybox-static cpio kmod xz-utils zstd  # tools/kernel-vm, the kernel test machine
  python3-apt                                           # its choice of Debian's packages (and its tests)
  udev iproute2                                         # udevd applying an instance's rules there; ip
  strace                                                # the evdev kernel tests: the loop's system calls
  clang llvm                                            # the asan stage; llvm-symbolizer
  python3-venv python3-setuptools python3-wheel         # the Python client installed with pip,
                                                        # offline, in its tests
)

as_root=()
if [[ $(id -u) -ne 0 ]] && command -v sudo >/dev/null; then as_root=(sudo); fi
need_root() {
  if [[ $(id -u) -ne 0 ]] && ((${#as_root[@]} == 0)); then
    echo "quickstart: $1 needs root, and sudo is not installed." >&2
    echo "quickstart: run this as root, or install sudo${2:+, or install yourself: $2}" >&2
    exit 2
  fi
}
apt_updated=0
apt_update() {  # WHY [PACKAGES]
  need_root "$1" "${2:-}"
  "${as_root[@]}" apt-get update -q
  apt_updated=1
}

# The names that differ between Debian releases, resolved here, from what this release's apt
# offers (never a list per release):
#   libclang-rt-N-dev  the runtime (libFuzzer, the sanitizers) of the clang-N the `clang`
#                      package depends on: clang-14 on Debian 12, clang-19 on Debian 13
#   the kernel's compiler  what the headers of the guest kernel (the one
#                      linux-image-<flavour> depends on) depend on to build modules:
#                      linux-compiler-gcc-12-x86 (gcc-12) on Debian 12, gcc-14 on Debian 13;
#                      setup builds gpio-sim, raw_gadget and the PWM simulator with it. The
#                      rule is tools/kernel-vm/resolve's (its COMPILER); tests/tools checks
#                      that both pick the same package
# apt-cache takes seconds a call where apt keeps no package cache, so the answer is kept
# (outside the repository) until apt's lists change.
release_packages() {
  local flavour=${HAPTICD_KERNEL_FLAVOUR:-amd64} memo key clang image compiler
  memo=${XDG_CACHE_HOME:-${HOME:-/tmp}/.cache}/hapticd/quickstart-$flavour-packages
  key=$(stat -c '%n %Y' /var/lib/apt/lists/*Packages* 2>/dev/null | sha256sum | cut -c1-16)
  if [[ $(head -n1 "$memo" 2>/dev/null) == "$key" ]]; then
    tail -n +2 "$memo"
    return
  fi
  depends() {  # PACKAGE... -> "package dependency" lines
    apt-cache depends "$@" 2>/dev/null | awk '/^[^ ]/ { p = $1 } $1 == "Depends:" { print p, $2 }'
  }
  local deps
  deps=$(depends clang "linux-image-$flavour")
  clang=$(awk '$1 == "clang" && $2 ~ /^clang-[0-9]+$/ { print $2; exit }' <<<"$deps")
  image=$(awk '$1 ~ /^linux-image-/ && $2 ~ /^linux-image-/ { print $2; exit }' <<<"$deps")
  [[ -n $clang && -n $image ]] || return 1
  compiler=$(depends "linux-headers-${image#linux-image-}" |
    awk '$2 ~ /^(linux-compiler-|gcc-[0-9])/ { print $2; exit }')
  [[ -n $compiler ]] || return 1
  mkdir -p "$(dirname "$memo")"
  printf '%s\n' "$key" "libclang-rt-${clang#clang-}-dev" "$compiler" >"$memo"
  tail -n +2 "$memo"
}
if [[ $mode == test || $mode == packages ]]; then
  packages+=("${test_packages[@]}")
  if ! names=$(release_packages); then
    # A fresh machine's apt knows no package before its first update.
    apt_update "looking up this release's package names (apt-get update)"
    names=$(release_packages) || {
      echo "quickstart: apt knows no clang or no linux-image-${HAPTICD_KERNEL_FLAVOUR:-amd64}" \
        "with its headers: is this Debian, with main in its sources?" >&2
      exit 2
    }
  fi
  mapfile -t -O "${#packages[@]}" packages <<<"$names"
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "quickstart: installing ${missing[*]}"
  ((apt_updated)) || apt_update "installing Debian packages" "${missing[*]}"
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# configure_and_build DIR CMAKE_ARGS... [-- TARGETS...]
# Unity builds (CMake's batches of 8 sources a translation unit): the headers (GoogleTest, json,
# Eigen, the standard library) parsed and their templates compiled once a batch, not once a
# file, where the three builds' compile time is most of the test command's (BENCHMARKS.md, "The
# test command's time"). A file's own names then share a batch with its neighbours': a test
# file's helpers and constants need names (or a header) of their own, and a local build without
# unity (the default) still proves each file includes what it uses.
configure_and_build() {
  local dir=$1 args=() targets=()
  shift
  while (($#)) && [[ $1 != -- ]]; do args+=("$1"); shift; done
  (($#)) && shift && targets=("$@")
  [[ -f $dir/CMakeCache.txt ]] ||
    cmake -S . -B "$dir" -G Ninja -DHAPTICD_WERROR=ON -DCMAKE_UNITY_BUILD=ON "${args[@]}"
  cmake --build "$dir" ${targets[@]+--target "${targets[@]}"}
}

case $mode in
  demo)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -- hapticd
    echo "quickstart: the daemon is build/service/hapticd; running the 3 s demo"
    exec build/service/hapticd run --duration 3 --log build/demo.hlog ;;
  build)
    configure_and_build build -DCMAKE_BUILD_TYPE=Release -- hapticd
    exit 0 ;;
  packages) exit 0 ;;
esac

stages=${HAPTICD_STAGES:-main asan tsan}
failed=()
report=()
# A stage runs in a subshell whose status is tested, where bash ignores `set -e`: each step
# that must stop its stage says `|| return` (a failed build must not go on to run old tests).
# run_stage NAME DIR FUNCTION: FUNCTION DIR builds in DIR and runs its tests there. ctest keeps
# an earlier run's list of failed tests when a later run passes, so it goes first: what
# failure_report reads is this run's.
run_stage() {
  local name=$1 dir=$2 start=$SECONDS status=0
  [[ " $stages " == *" $name "* ]] || return 0
  echo "quickstart: === stage $name ==="
  rm -f "$dir/Testing/Temporary/LastTestsFailed.log"
  ("$3" "$dir") || status=$?
  report+=("$(printf '%-5s %4d s  %s' "$name" $((SECONDS - start)) \
    "$([[ $status -eq 0 ]] && echo ok || echo "FAILED ($status)")")")
  [[ $status -eq 0 ]] || failed+=("$name $dir")
}

# The Release build runs what needs it: the kernel and systemd test machines (timed against an
# emulator, and what a user runs), the coupling designs end to end (minutes of CPU under a
# sanitizer), the plot tool, the layering probes and the Python client against the daemon a
# user runs. The rest of the suite runs once, under
# the sanitizers (stage asan), which catch there what a Release run of it would and more; gcc
# compiles the daemon and every test the machines run with warnings as errors, clang the rest.
stage_main() {
  configure_and_build "$1" -DCMAKE_BUILD_TYPE=Release -- hapticd_release_tests || return
  cd "$1" && ctest --output-on-failure -j "$(nproc)" \
    -L "^(kernel|systemd|design|slow|plot|layering|python)$"
}
# clang, because libFuzzer ships with it: one instrumented build serves both the suite under
# the sanitizers and the fuzz targets (fuzz/README.md), where two builds of the same code
# took a third of the test command. Line tables are all a sanitizer's report needs (full
# debug information: 6 % more compile time, objects 6 times larger, e.g. sim/plant.cpp).
build_asan() {  # DIR
  local fuzz=ON
  [[ ${HAPTICD_FUZZ:-1} == 0 ]] && fuzz=OFF
  CC=clang CXX=clang++ configure_and_build "$1" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" \
    -DHAPTICD_SANITIZE=address -DHAPTICD_FUZZ=$fuzz -DHAPTICD_BUILD_BENCHMARKS=OFF \
    -DHAPTICD_BUILD_KERNEL_TESTS=OFF
}
stage_asan() {
  [[ ${HAPTICD_FUZZ:-1} == 0 ]] && echo "quickstart: HAPTICD_FUZZ=0: fuzz targets skipped on purpose"
  build_asan "$1" || return
  # One boot of the kernel test machine per run: the main stage's; its binaries are not even
  # built here (a sixth of the build). Not the layering probes (they compile, run nothing) nor
  # the plot tool's test (Python drawing what the Cli tests' commands print): the main stage
  # runs both, and a sanitizer finds nothing in them. Nor the coupling designs end to end
  # (labels design and slow: 20 s and 50 s of CPU in Release, SDP solves and long simulated
  # `verify` runs): the analysis tests run the design's code, one whole design included.
  cd "$1" && ctest --output-on-failure -j "$(nproc)" -LE "^(layering|plot|design|slow|python)$"
}
# Without the CAN, GPIO, HID, evdev, serial and Falcon drivers: the loop, telemetry and service
# tests run the sim device, so those drivers' threads are not exercised here (their own tests run
# in asan and in the kernel test machine), and leaving them out leaves 55 of this stage's 83
# build steps.
build_tsan() {  # DIR
  configure_and_build "$1" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG" -DHAPTICD_SANITIZE=thread \
    -DHAPTICD_BUILD_BENCHMARKS=OFF -DHAPTICD_WITH_CAN=OFF -DHAPTICD_WITH_GPIO=OFF \
    -DHAPTICD_WITH_HID=OFF -DHAPTICD_WITH_EVDEV=OFF -DHAPTICD_WITH_SERIAL=OFF \
    -DHAPTICD_WITH_FALCON=OFF \
    -- hapticd hapticd_loop_tests hapticd_telemetry_tests hapticd_service_tests \
    hapticd_service_unit_tests
}
stage_tsan() {
  build_tsan "$1" || return
  # Not the two tests of a signal at start-up: TSan intercepts signals and defers them to its
  # own safe points, and one random-signal trial in three loaded runs lost a start-up signal
  # that way, and one stop during start-up in a Debian 12 check ended the daemon by the
  # deferred SIGTERM itself (exit by signal, not 0): never in the main or asan stage, which
  # run both. This stage is for data races.
  cd "$1" && ctest --output-on-failure -j "$(nproc)" -L "^(loop|telemetry|service)$" \
    -E "^(FaultInjection.RandomSignalsAtRandomMomentsAlwaysEndSafely|CliSignals.AStopDuringStartUpNeverEnablesOutput)$"
}

# What failed, again at the very end: a log read from its tail (CI keeps only the last part)
# still names each failed test and its failure, not only the stage. From ctest's own record of
# its last run: the failed tests' names, and for each the lines of its output that say why
# (from the first that names a failure: GoogleTest's file:line, a command's error), at most
# 12 a test.
failure_report() {  # STAGE DIR
  local failed_list=$2/Testing/Temporary/LastTestsFailed.log
  [[ -s $failed_list ]] || return 0
  echo "quickstart: stage $1: failed tests (whole output above, and in $2/Testing/Temporary/LastTest.log):"
  awk -F: 'NR == FNR { sub(/^[0-9]+:/, ""); sub(/ .*/, ""); want[$0] = 1; next }
    /^[0-9]+\/[0-9]+ Test: / { name = $0; sub(/^[^:]*: /, "", name); sub(/ .*/, "", name)
                               on = (name in want); n = 0; if (on) print "  " name; next }
    on && /<end of output>/ { on = 0 }
    on && !n && /(^\/.*:[0-9]+$|Failure|FAILED|[Ee]rror|Expected|timed? ?out|refused)/ { n = 1 }
    on && n && n <= 12 && !/^$/ { print "    " substr($0, 1, 200); n++ }' "$failed_list" "$2/Testing/Temporary/LastTest.log"
}

# The sanitizer stages' builds start in the background at the lowest priority (SCHED_IDLE)
# when the main stage does: they take only what the main stage leaves idle (an emulated guest
# waiting on its tests' timers leaves more than a core), and the guest's threads preempt them
# at once, so the tests keep the machine they are timed on. Each sanitizer stage waits for its
# own build, then builds what is left (nothing, or what a failed background build stopped at:
# its errors are printed there).
background_builds() {  # STAGE DIR...
  while (($#)); do
    local s=$1 dir=$2
    shift 2
    [[ " $stages " == *" $s "* ]] || continue
    echo "quickstart: === $s build (background, idle priority) ==="
    "build_$s" "$dir" || echo "quickstart: the $s build failed in the background; its stage builds again"
    echo "quickstart: === $s built"
  done
}
dir_asan=build-asan-clang dir_tsan=build-tsan  # each stage's build directory
background=
if [[ " $stages " == *" main "* && " $stages " =~ \ (asan|tsan)\  ]] && command -v chrt >/dev/null; then
  echo "quickstart: building the sanitizer stages at idle priority beside main (build-background.log)"
  chrt --idle 0 bash -c "$(declare -f configure_and_build build_asan build_tsan background_builds)
    stages='$stages'; background_builds asan $dir_asan tsan $dir_tsan" >build-background.log 2>&1 &
  background=$!
fi
# Until the background build of stage $1 is over (or all of them are): the asan stage runs its
# tests while the tsan build goes on beside them, at idle priority still.
await_background() {
  [[ -n $background && " $stages " == *" $1 "* ]] || return 0
  echo "quickstart: waiting for the background $1 build (build-background.log)"
  while [[ -n $(jobs -r -p) ]] && ! grep -q "=== $1 built" build-background.log; do sleep 2; done
}
run_stage main build stage_main
await_background asan
run_stage asan "$dir_asan" stage_asan
await_background tsan
run_stage tsan "$dir_tsan" stage_tsan
# The kernel tests that passed only on their second run in the guest (kernel_test_report):
# passed, and named here; the first run's failure is in build/Testing/Temporary/LastTest.log.
second_runs() {
  [[ " $stages " == *" main "* && -s build/Testing/Temporary/LastTest.log ]] || return 0
  # sed, not grep: no line found is no failure (the script runs under pipefail and -e).
  sed -n 's/^kernel test passed on its second run: \([^;]*\);.*/quickstart: passed on its second run in the kernel test machine: \1/p' \
    build/Testing/Temporary/LastTest.log | sort -u
}
second_runs
for s in ${failed[@]+"${failed[@]}"}; do
  failure_report $s  # "NAME DIR": no stage name or directory has a space
done
echo "quickstart: stage  time    result"
printf 'quickstart: %s\n' "${report[@]}"
if ((${#failed[@]})); then
  echo "quickstart: FAILED: ${failed[*]%% *}" >&2
  exit 1
fi
echo "quickstart: every stage passed"
