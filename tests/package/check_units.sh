#!/usr/bin/env bash
# Checks the systemd units of deploy/debian and prints their exposure:
#   - `systemd-analyze verify` finds nothing to say (a warning such as an
#     unknown key fails too), on copies whose ExecStart points at the build
#     tree, since the package's /usr/bin is not installed here;
#   - `systemd-analyze security --offline=true` scores each unit "OK" or
#     better (exposure below 5.0; the requirement is "MEDIUM", below 7.5).
# Usage: tests/package/check_units.sh <source dir> <build bin dir>
set -euo pipefail

src="${1:?usage: check_units.sh <source dir> <build bin dir>}"
bin="${2:?usage: check_units.sh <source dir> <build bin dir>}"
units="$src/deploy/debian"
max_exposure=49  # tenths: 4.9, the top of "OK"

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
for unit in picksight-video-server.service picksight-vision@.service picksight-web.service; do
  [ -f "$units/$unit" ] || { echo "FAIL: no $units/$unit" >&2; exit 1; }
  sed "s|^ExecStart=/usr/bin/|ExecStart=$bin/|" "$units/$unit" >"$work/$unit"
  grep -q "^ExecStart=$bin/" "$work/$unit" || { echo "FAIL: $unit: ExecStart not in /usr/bin" >&2; exit 1; }
done

status=0
# PID 1 is not systemd here: verify loads the units by itself. The template
# is verified as an instance, as systemctl would start it.
out="$(SYSTEMD_UNIT_PATH="$work:" systemd-analyze verify --man=no \
         picksight-video-server.service picksight-vision@cam0.service picksight-web.service \
         2>&1)" && rc=0 || rc=$?
if [ "$rc" != 0 ] || [ -n "$out" ]; then
  echo "FAIL: systemd-analyze verify (status $rc) complains:" >&2
  printf '%s\n' "$out" >&2
  status=1
else
  echo "systemd-analyze verify: picksight-video-server.service picksight-vision@cam0.service picksight-web.service: clean"
fi

for unit in picksight-video-server.service picksight-vision@.service picksight-web.service; do
  out="$(systemd-analyze security --no-pager --offline=true --threshold="$max_exposure" \
           "$work/$unit" 2>&1)" && ok=1 || ok=0
  score="$(printf '%s\n' "$out" | grep 'Overall exposure level' || true)"
  if [ -z "$score" ]; then
    echo "FAIL: systemd-analyze security $unit printed no score:" >&2
    printf '%s\n' "$out" >&2
    status=1
    continue
  fi
  echo "systemd-analyze security: ${score#→ }"
  if [ "$ok" = 0 ]; then
    echo "FAIL: $unit is above exposure $max_exposure/100; what it misses:" >&2
    printf '%s\n' "$out" | grep '✗' >&2 || true
    status=1
  fi
done
exit "$status"
