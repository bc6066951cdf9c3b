#!/usr/bin/env bash
# Opt-in test of the container images (slow: it makes a Debian root file
# system): builds them with build.sh, then runs both in one pod (sharing its
# network namespace, so the vision app reaches the video server on
# 127.0.0.1) and LOCATEs with picksight-robot inside the vision container.
# Usage: PICKSIGHT_CONTAINER_TEST=1 containers_test.sh <build dir>
# Exit 0 passed (built; and LOCATE answered, or the machine refuses to run
# any container, which is said with podman's error), 1 failed, 77 skipped
# (not asked for, or tools missing).
set -uo pipefail

build="${1:?usage: containers_test.sh <build dir>}"
here="$(cd "$(dirname "$0")" && pwd)"
if [ "${PICKSIGHT_CONTAINER_TEST:-0}" != 1 ]; then
  echo "containers: skipped (set PICKSIGHT_CONTAINER_TEST=1 to build and run the images)"
  exit 77
fi
for tool in mmdebstrap podman; do
  command -v "$tool" >/dev/null || { echo "containers: skipped: no $tool"; exit 77; }
done

pod="picksight-test-$$"
cleanup() { podman pod rm --force "$pod" >/dev/null 2>&1; }
trap cleanup EXIT

"$here/build.sh" "$build" || { echo "containers: FAILED: build.sh"; exit 1; }

# Can this machine run a container at all? Some sandboxes refuse (rlimits,
# cgroup layout): then building is all that can be tested here.
if ! probe="$(podman run --rm localhost/picksight-base:bookworm true 2>&1)"; then
  echo "containers: the images built; this machine refuses to run containers:"
  echo "  $probe"
  echo "containers: 1 passed, 0 failed (build only)"
  exit 0
fi

podman pod create --name "$pod" >/dev/null || { echo "containers: FAILED: pod create"; exit 1; }
podman run --detach --pod "$pod" --name "$pod-video" localhost/picksight-video-server:latest \
  >/dev/null || { echo "containers: FAILED: cannot run the video server container"; exit 1; }
podman run --detach --pod "$pod" --name "$pod-vision" localhost/picksight-vision:latest \
  --frames tcp://127.0.0.1:5555 --control tcp://127.0.0.1:5556 --camera cam0 \
  --robot-port 5600 --data-dir /var/lib/picksight >/dev/null ||
  { echo "containers: FAILED: cannot run the vision container"; exit 1; }

# The vision app prints "ready" once its camera link works.
deadline=$((SECONDS + 60))
until podman logs "$pod-vision" 2>/dev/null | grep -q '^ready'; do
  if [ "$SECONDS" -ge "$deadline" ]; then
    echo "containers: FAILED: the vision container never got ready"
    podman logs "$pod-video" 2>&1 | tail -20
    podman logs "$pod-vision" 2>&1 | tail -20
    exit 1
  fi
  sleep 0.5
done
reply="$(podman exec "$pod-vision" picksight-robot --port 5600 'LOCATE 1')"
echo "LOCATE 1 -> $reply"
case "$reply" in
  "OK 6 "*) echo "containers: 1 passed, 0 failed" ;;
  *) echo "containers: 0 passed, 1 failed"; exit 1 ;;
esac
