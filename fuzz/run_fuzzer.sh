#!/usr/bin/env bash
# How ctest runs a fuzz target (fuzz/CMakeLists.txt); tools/fuzz.sh uses it for long runs.
#   run_fuzzer.sh replay EXE [FLAGS...] -- DIR...
#     runs every file under the DIRs once (libFuzzer's file mode: nothing is mutated or
#     written); any crash, sanitizer report, leak or -timeout fails.
#   run_fuzzer.sh fuzz EXE WORK [FLAGS...] -- DIR...
#     empties WORK, then fuzzes with WORK/corpus as the corpus it grows (the DIRs are read as
#     seeds, never written) and WORK/findings/ for crash inputs.
# DIRs that do not exist are skipped, so a target may have no regressions yet.
set -euo pipefail
mode=$1 exe=$2
shift 2
if [[ $mode == fuzz ]]; then
  work=$1
  shift
fi
flags=()
while (($#)) && [[ $1 != -- ]]; do
  flags+=("$1")
  shift
done
(($#)) && shift
dirs=()
for d in "$@"; do
  [[ -d $d ]] && dirs+=("$d")
done

case $mode in
  replay)
    mapfile -t files < <(find "${dirs[@]}" -type f ! -name '.*' | sort)
    echo "replaying ${#files[@]} inputs from ${dirs[*]}"
    ((${#files[@]})) || exit 0
    exec "$exe" "${flags[@]}" "${files[@]}" ;;
  fuzz)
    rm -rf "$work"
    mkdir -p "$work/corpus" "$work/findings"
    exec "$exe" "${flags[@]}" -artifact_prefix="$work/findings/" "$work/corpus" "${dirs[@]}" ;;
  *)
    echo "usage: run_fuzzer.sh replay|fuzz ..." >&2
    exit 2 ;;
esac
