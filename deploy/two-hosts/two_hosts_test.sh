#!/usr/bin/env bash
# The two-host example on one machine: network namespaces stand for the
# camera PC, the vision PC, a viewer and a robot controller, joined by veth
# pairs to a bridge in a "switch" namespace (10.77.0.0/24, addresses that
# exist only inside these namespaces). The real binaries of a build tree run
# in them with the example's files (camera-pc/, vision-pc/); the robot
# LOCATEs across the namespaces and the viewer receives frames.
#
# Usage: two_hosts_test.sh <build bin dir> <build python dir>
# Exit 0 passed, 1 failed, 77 skipped (not root, or namespaces refused).
set -uo pipefail

bin="${1:?usage: two_hosts_test.sh <bin dir> <python dir>}"
pydir="${2:?usage: two_hosts_test.sh <bin dir> <python dir>}"
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
readonly SKIP=77

# Unique names per run: parallel runs and leftovers of a killed run never clash.
tag="ps$$"
ns_switch="$tag-switch" ns_cam="$tag-cam" ns_vision="$tag-vision"
ns_viewer="$tag-viewer" ns_robot="$tag-robot"
work="$(mktemp -d /tmp/picksight-two-hosts-XXXXXX)"
pids=()
created=()

cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null; done
  for pid in "${pids[@]}"; do wait "$pid" 2>/dev/null; done
  for ns in "${created[@]}"; do ip netns delete "$ns" 2>/dev/null; done
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

if [ "$(id -u)" -ne 0 ]; then
  echo "two-hosts: skipped: network namespaces need root"
  exit $SKIP
fi
if ! ip netns add "$ns_switch" 2>"$work/netns.err"; then
  echo "two-hosts: skipped: ip netns add refused: $(cat "$work/netns.err")"
  exit $SKIP
fi
created+=("$ns_switch")

passed=0 failed=0
check() {  # check <description> <command...>: one result line per check
  local what="$1"
  shift
  if "$@" >"$work/check.out" 2>&1; then
    passed=$((passed + 1))
    echo "ok: $what"
  else
    failed=$((failed + 1))
    echo "FAILED: $what"
    sed 's/^/    /' "$work/check.out"
  fi
}
die() {
  echo "two-hosts: $*" >&2
  for log in "$work"/*.log; do [ -f "$log" ] && { echo "--- $log"; tail -20 "$log"; }; done >&2
  exit 1
}

# wait_line <file> <prefix> <seconds>: polls until a line starts with prefix.
wait_line() {
  local deadline=$((SECONDS + $3))
  until grep -q "^$2" "$1" 2>/dev/null; do
    [ "$SECONDS" -lt "$deadline" ] || return 1
    sleep 0.1
  done
}

# -------------------------------------------------------------- the network
ip -n "$ns_switch" link add br0 type bridge || die "no bridge support"
ip -n "$ns_switch" link set br0 up
address=1
for ns in "$ns_cam" "$ns_vision" "$ns_viewer" "$ns_robot"; do
  ip netns add "$ns" || die "ip netns add $ns failed"
  created+=("$ns")
  port="p$address-$$"
  port="${port:0:15}"
  # Made in the switch namespace, its peer moved straight into the host's:
  # nothing of it ever exists in the machine's own namespace.
  ip -n "$ns_switch" link add "$port" type veth peer name eth0 netns "$ns" || die "veth failed"
  ip -n "$ns_switch" link set "$port" master br0 up
  ip -n "$ns" link set lo up
  ip -n "$ns" addr add "10.77.0.$address/24" dev eth0
  ip -n "$ns" link set eth0 up
  address=$((address + 1))
done

# ------------------------------------------------------------ the programs
# Camera PC: the example's video server configuration as it is.
ip netns exec "$ns_cam" "$bin/picksight-video-server" --config "$here/camera-pc/video-server.yaml" \
  >"$work/video-server.log" 2>&1 &
pids+=($!)
wait_line "$work/video-server.log" "control " 20 || die "the video server did not start"

# Vision PC: two vision apps, one per camera and robot, as the example starts them.
for instance in line1 line2; do
  PICKSIGHT_BIN="$bin" ip netns exec "$ns_vision" "$here/vision-pc/start-vision.sh" "$instance" \
    "$work/state" >"$work/vision-$instance.log" 2>&1 &
  pids+=($!)
done
for instance in line1 line2; do
  wait_line "$work/vision-$instance.log" "ready" 30 || die "vision app $instance did not start"
done

# ---------------------------------------------------------------- the checks
robot() { ip netns exec "$ns_robot" "$bin/picksight-robot" --host 10.77.0.2 "$@"; }
locate_finds() {  # locate_finds <port> <parts>: LOCATE 1 returns that many parts
  local reply
  reply="$(robot --port "$1" 'LOCATE 1')" || { echo "$reply"; return 1; }
  echo "$reply"
  [ "$(echo "$reply" | cut -d' ' -f1,2)" = "OK $2" ]
}
status_names() {  # status_names <port> <camera>
  robot --port "$1" STATUS | grep -q " camera=$2 "
}
check "robot 1 LOCATEs on line1 across the namespaces (6 parts)" locate_finds 5600 6
check "robot 2 LOCATEs on line2 across the namespaces (4 parts)" locate_finds 5601 4
check "vision app on 5600 watches line1" status_names 5600 line1
check "vision app on 5601 watches line2" status_names 5601 line2
check "the viewer lists the cameras through the control socket" \
  bash -c "ip netns exec '$ns_viewer' '$bin/picksight-cam' --control tcp://10.77.0.1:5556 list | grep -q line2"
check "the viewer receives line2's frames (python FrameSubscriber)" \
  bash -c "ip netns exec '$ns_viewer' env PYTHONPATH='$pydir' /usr/bin/python3 \
    '$repo/python/examples/watch_frames.py' --frames tcp://10.77.0.1:5555 --camera line2 \
    --count 3 | grep -q '^received=3 '"
check "no 10.77 address exists outside the namespaces" \
  bash -c "! ip -4 addr show | grep -q 'inet 10\.77\.'"

echo "two-hosts: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
