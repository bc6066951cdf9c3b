#!/usr/bin/env bash
# Short libFuzzer run of a request fuzzer (the robot's by default), for CI.
# usage: tests/fuzz/run_fuzz.sh BUILD_DIR [SECONDS [FUZZER CORPUS_DIR]]
#   BUILD_DIR configured with -DCMAKE_CXX_COMPILER=clang++ -DPICKSIGHT_FUZZ=ON
# The seed corpus is copied: the run never writes into the source tree.
set -euo pipefail
build=$(cd "${1:?usage: run_fuzz.sh BUILD_DIR [SECONDS]}" && pwd)
seconds=${2:-20}
root=$(cd "$(dirname "$0")/../.." && pwd)
fuzzer="$build/bin/${3:-picksight-fuzz-robot-request}"
corpus=${4:-$root/fuzz/corpus}
[[ -x $fuzzer ]] || { echo "run_fuzz.sh: $fuzzer not built (PICKSIGHT_FUZZ=ON with clang)" >&2; exit 2; }
work=$(mktemp -d /tmp/picksight-fuzz-run-XXXXXX)
trap 'rm -rf "$work"' EXIT
cp "$corpus"/* "$work"/
cd "$work"
# One worker: the CI machines have 2 shared cores. Leaks are findings too.
"$fuzzer" -max_total_time="$seconds" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$work"
