#!/usr/bin/env bash
# Short libFuzzer run of one of the fuzzers, for CI.
# usage: tests/fuzz/run_fuzz.sh BUILD_DIR [SECONDS] [robot|control|modbus]
#   BUILD_DIR configured with -DCMAKE_CXX_COMPILER=clang++ -DPICKSIGHT_FUZZ=ON
#   robot (default): the robot request fuzzer, seeds in fuzz/corpus
#   control: the video server's control request fuzzer, seeds in
#            fuzz/control_corpus; inputs up to 70000 bytes, past the 64 KiB limit
#   modbus: the PLC port's Modbus TCP byte stream, seeds in fuzz/corpus_modbus
# The seed corpus is copied: the run never writes into the source tree.
set -euo pipefail
build=$(cd "${1:?usage: run_fuzz.sh BUILD_DIR [SECONDS] [robot|control|modbus]}" && pwd)
seconds=${2:-20}
which=${3:-robot}
root=$(cd "$(dirname "$0")/../.." && pwd)
case $which in
  robot) fuzzer="$build/bin/picksight-fuzz-robot-request" corpus="$root/fuzz/corpus" max_len=4096 ;;
  control) fuzzer="$build/bin/picksight-fuzz-control-request" corpus="$root/fuzz/control_corpus" max_len=70000 ;;
  modbus) fuzzer="$build/bin/picksight-fuzz-modbus-request" corpus="$root/fuzz/corpus_modbus" max_len=4096 ;;
  *) echo "run_fuzz.sh: unknown fuzzer '$which' (robot, control or modbus)" >&2; exit 2 ;;
esac
[[ -x $fuzzer ]] || { echo "run_fuzz.sh: $fuzzer not built (PICKSIGHT_FUZZ=ON with clang)" >&2; exit 2; }
work=$(mktemp -d /tmp/picksight-fuzz-run-XXXXXX)
trap 'rm -rf "$work"' EXIT
cp "$corpus"/* "$work"/
cd "$work"
# One worker: the CI machines have 2 shared cores. Leaks are findings too.
"$fuzzer" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 -rss_limit_mb=2048 \
  -print_final_stats=1 "$work"
