#!/usr/bin/env bash
# The README's quick start: installs the dependencies (Debian 12, as root),
# builds, then runs the demo (`demo`) or the whole test suite (`test`).
set -euo pipefail
cd "$(dirname "$0")/.."

what="${1:-demo}"
case "$what" in
  demo|test) ;;
  *) echo "usage: deploy/quickstart.sh demo|test" >&2; exit 2 ;;
esac

./deploy/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build -j"$(nproc)"

if [ "$what" = demo ]; then
  exec ./build/bin/picksight-demo
fi
# Tests start real processes on free ports; two at a time fits 2 cores.
cd build
exec ctest --output-on-failure -j2 --timeout 300
