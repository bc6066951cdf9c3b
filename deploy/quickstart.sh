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

# A new build tree uses Ninja (it keeps both cores busy where Make waits for
# a library before compiling what uses it). A tree made earlier keeps its
# generator and settings: CMake refuses to switch generators in place.
config=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
if [ ! -f build/CMakeCache.txt ]; then
  config+=(-G Ninja)
  # A tree made for the tests gets line tables only: backtraces keep their
  # functions, files and lines, and gcc compiles about a quarter faster
  # (docs/CI.md). The Debian package is stripped either way.
  # And links with lld, four times faster than GNU ld on a test binary, and
  # precompiles the headers most sources include (a fifth off the build;
  # cmake/PrecompiledHeaders.cmake).
  if [ "$what" = test ]; then
    config+=(-DPICKSIGHT_DEBUG_INFO=lines -DPICKSIGHT_LINKER=lld -DPICKSIGHT_PCH=ON)
  fi
fi
cmake -S . -B build "${config[@]}"
cmake --build build -j"$(nproc)"

if [ "$what" = demo ]; then
  exec ./build/bin/picksight-demo
fi
# Tests start real processes on free ports; two at a time. They wait on
# those most of the time (one run: 1337 test-seconds on 415 CPU seconds):
# CI gives the idle CPU to its sanitizer build (.ci/run, docs/CI.md).
cd build
exec ctest --output-on-failure -j2 --timeout 300
