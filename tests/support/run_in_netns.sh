#!/bin/sh
# Runs a test command in a network namespace of its own, with only loopback
# up, so that tests holding a fixed port (Aravis's fake camera answers GVCP
# on UDP 3956 of 127.0.0.1) do not collide with a concurrent run of the same
# tests (another build tree, another ctest). Where a namespace cannot be made
# (not root, no iproute2, no CAP_SYS_ADMIN in a container) the command runs
# directly, as before, and such runs must not overlap.
#
# Used as the CROSSCOMPILING_EMULATOR of the test executable, which
# catch_discover_tests puts in front of the listing and of every test.
# Usage: run_in_netns.sh <command> [args...]
#        run_in_netns.sh --check   (exit 0 when namespaces can be made)
set -u

name="picksight-test-$$-$(od -An -N4 -tx4 /dev/urandom | tr -d ' ')"

make_namespace() {
  [ "$(id -u)" = 0 ] || return 1
  command -v ip >/dev/null 2>&1 || return 1
  ip netns add "$name" 2>/dev/null || return 1
  if ! ip -n "$name" link set lo up 2>/dev/null; then
    ip netns delete "$name" 2>/dev/null
    return 1
  fi
}

if [ "${1:-}" = "--check" ]; then
  make_namespace || exit 1
  ip netns delete "$name"
  exit 0
fi

# Namespaces of runs that were killed outright (SIGKILL skips the trap
# below: ctest's timeout does that) go when the next run starts.
remove_stale() {
  ip netns list 2>/dev/null | sed -n 's/^\(picksight-test-[0-9]*-[0-9a-f]*\).*/\1/p' |
    while read -r stale; do
      pid="${stale#picksight-test-}"
      pid="${pid%%-*}"
      kill -0 "$pid" 2>/dev/null || ip netns delete "$stale" 2>/dev/null
    done
}

if [ "${PICKSIGHT_NO_NETNS:-0}" != 1 ] && make_namespace; then
  remove_stale
  trap 'ip netns delete "$name" 2>/dev/null' EXIT
  trap 'exit 143' TERM
  trap 'exit 130' INT
  # The test may change the namespace's own firewall: it knows it is in one.
  ip netns exec "$name" env PICKSIGHT_TEST_NETNS="$name" "$@"
  exit $?
fi
exec "$@"
