#!/usr/bin/env bash
# The libFuzzer targets of fuzz/ (fuzz/README.md), built with clang in their own directory.
#   tools/fuzz.sh build                  configure (first time) and build the targets
#   tools/fuzz.sh test                   build, then the ctest tests labelled fuzz: every seed
#                                        and regression input replayed once, then a few seconds
#                                        of fuzzing per target (what tools/quickstart.sh test runs)
#   tools/fuzz.sh long [SECONDS] [TARGET...]
#                                        fuzz each target (default: all) for SECONDS (default
#                                        3600), one after another at nice 10, carrying on past
#                                        crashes; the corpus grows in BUILD/long/TARGET/corpus
#                                        across runs, crash inputs land in BUILD/long/TARGET/findings,
#                                        the summary gives executions and coverage
#   tools/fuzz.sh minimize TARGET INPUT NAME
#                                        shrinks a crash input into fuzz/regressions/TARGET/NAME,
#                                        replayed by every test run from then on
# HAPTICD_FUZZ_BUILD overrides the build directory (default build-fuzz); HAPTICD_FUZZ_TIMEOUT
# the seconds after which one input is a finding in long runs (default 5; on a machine busy
# with other work a starved input looks slow, so raise it there and replay what it finds).
set -euo pipefail
cd "$(dirname "$0")/.."
build=${HAPTICD_FUZZ_BUILD:-build-fuzz}
targets=(config_gate set_override log_reader log_reader_crc can_codec gpio_decoder control_socket
         hid_codec)
declare -A dict=([config_gate]=config [set_override]=set_override [log_reader]=log
                 [log_reader_crc]=log [can_codec]=can [gpio_decoder]=gpio [control_socket]=control
                 [hid_codec]=hid)

# clang, libFuzzer's runtime and llvm-symbolizer (for readable stacks): the quick start
# installs them with the test command's packages, under this release's names.
install_missing() { tools/quickstart.sh packages; }

build_targets() {
  install_missing
  [[ -f $build/CMakeCache.txt ]] ||
    CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DHAPTICD_FUZZ=ON -DHAPTICD_BUILD_TESTS=OFF -DHAPTICD_BUILD_BENCHMARKS=OFF
  cmake --build "$build" --target fuzz_targets
}

# Fuzzes one target in one process, so what it learns (and the gate memo of
# fuzz/support/config_oracle.cpp) lasts the whole run; after a crash it saves the input and
# starts again on the grown corpus until the time is up. The regressions are not seeds here:
# one that still crashes would end every restart at once (tools/fuzz.sh test replays them).
long_run() {
  local t=$1 seconds=$2 work=$build/long/$1
  mkdir -p "$work/corpus" "$work/findings"
  "$build/fuzz/fuzz_make_log_seeds" "$build/fuzz/seeds/log" >/dev/null
  local seeds=(fuzz/corpus/"$t") dirs=() d
  [[ $t == config_gate ]] && seeds+=(config)
  [[ $t == log_reader* ]] && seeds+=("$build/fuzz/seeds/log")
  for d in "${seeds[@]}"; do [[ -d $d ]] && dirs+=("$d"); done
  echo "fuzz: $t for $seconds s, log in $work/fuzz.log"
  : >"$work/fuzz.log"
  local end=$((SECONDS + seconds)) found
  while ((SECONDS < end)); do
    found=$(find "$work/findings" -type f | wc -l)
    nice -n 10 "$build/fuzz/${t}_fuzzer" -timeout="${HAPTICD_FUZZ_TIMEOUT:-5}" -rss_limit_mb=2048 \
      -print_funcs=0 -max_total_time=$((end - SECONDS)) -dict="fuzz/dict/${dict[$t]}.dict" \
      -artifact_prefix="$work/findings/" -print_final_stats=1 "$work/corpus" "${dirs[@]}" \
      >>"$work/fuzz.log" 2>&1 && break
    # No new crash input: it failed to start, or crashed again on one it already saved.
    (($(find "$work/findings" -type f | wc -l) > found)) ||
      { echo "fuzz: $t stopped without a new finding, see $work/fuzz.log" >&2; break; }
  done
  local execs
  execs=$(awk -F: '/^stat::number_of_executed_units/ { n += $2 } END { print n + 0 }' "$work/fuzz.log")
  echo "fuzz: $t: $execs executions; last status: $(grep -E '^#[0-9]+' "$work/fuzz.log" | tail -n 1)"
  echo "fuzz: $t: $(find "$work/findings" -type f | wc -l) crash inputs in $work/findings"
}

case "${1:-}" in
  build)
    build_targets ;;
  test)
    build_targets
    cd "$build" && exec ctest -L fuzz --output-on-failure -j "$(nproc)" ;;
  long)
    seconds=${2:-3600}
    (($# > 2)) && targets=("${@:3}")
    build_targets
    for t in "${targets[@]}"; do long_run "$t" "$seconds"; done ;;
  minimize)
    (($# == 4)) || { echo "usage: tools/fuzz.sh minimize TARGET INPUT NAME" >&2; exit 2; }
    build_targets
    mkdir -p "fuzz/regressions/$2"
    "$build/fuzz/$2_fuzzer" -minimize_crash=1 -runs=20000 -timeout=5 \
      -exact_artifact_path="fuzz/regressions/$2/$4" "$3" ;;
  *)
    echo "usage: tools/fuzz.sh build|test|long [SECONDS] [TARGET...]|minimize TARGET INPUT NAME" >&2
    exit 2 ;;
esac
