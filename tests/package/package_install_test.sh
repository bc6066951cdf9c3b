#!/usr/bin/env bash
# The Debian package as a cell gets it: builds picksight_<version>_amd64.deb
# from this build tree (cpack), checks its contents, installs it with
# `dpkg -i`, runs the installed binaries as their units would (as the
# picksight user, with the unit's ExecStart and the installed example
# configuration; only the ports are made free ones, and systemd's
# StateDirectory= is made by hand, since no systemd runs here), LOCATEs
# through the robot port, then `dpkg --purge`s and checks that nothing of
# the package is left. The picksight user stays (Debian keeps system users).
# Prints the package's size and dependencies.
#
# Root only, and it installs into this machine's /usr: without root, dpkg
# or setpriv, or when a picksight package is already installed (not ours to
# remove), it exits 77, which CTest reports as skipped.
# Usage: tests/package/package_install_test.sh <build dir> <cpack>
set -uo pipefail

build="${1:?usage: package_install_test.sh <build dir> <cpack>}"
cpack="${2:?usage: package_install_test.sh <build dir> <cpack>}"
SKIP=77

skip() { echo "SKIPPED: $*"; exit "$SKIP"; }
fail() { echo "FAIL: $*" >&2; exit 1; }

[ "$(id -u)" = 0 ] || skip "needs root (dpkg -i into this machine)"
for tool in dpkg dpkg-deb setpriv flock getent openssl curl; do
  command -v "$tool" >/dev/null || skip "no $tool"
done
[ -w /var/lib/dpkg ] || skip "dpkg's database is not writable"

# One package test at a time on this machine (several build trees may run
# their suites at once); dpkg itself refuses a second dpkg anyway.
exec 9>/run/lock/picksight-package-test.lock
flock -w 150 9 || fail "another package test held the lock for 150 s"

# Present while this test has the package installed, with the ids of the
# services it started: a run killed before its purge (a CTest timeout
# sends SIGKILL) leaves it, and the next run stops and purges what that
# run left instead of refusing to touch it.
marker=/run/lock/picksight-package-test.installed
if dpkg-query -W -f='${Status}' picksight 2>/dev/null | grep -q 'installed'; then
  [ -e "$marker" ] || skip "a picksight package is already installed on this machine; not touching it"
  echo "purging the package an interrupted run left installed"
  while read -r pid; do
    case "$(readlink "/proc/$pid/exe" 2>/dev/null)" in
      /usr/bin/picksight-*) kill -KILL "$pid" ;;
    esac
  done <"$marker"
  dpkg --purge picksight >/dev/null || fail "cannot purge the package an interrupted run left"
fi
rm -f "$marker"

work="$(mktemp -d)"
pids=()
installed=0
cleanup() {
  for pid in "${pids[@]}"; do kill -KILL "$pid" 2>/dev/null; done
  # Always purge what we installed, even after a failure.
  [ "$installed" = 1 ] && dpkg --purge picksight >/dev/null 2>&1 && rm -f "$marker"
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 1' INT TERM

# --- build ------------------------------------------------------------------
"$cpack" -G DEB --config "$build/CPackConfig.cmake" -B "$work/pkg" >"$work/cpack.log" 2>&1 ||
  { cat "$work/cpack.log" >&2; fail "cpack"; }
debs=("$work"/pkg/picksight_*_amd64.deb)
[ "${#debs[@]}" = 1 ] && [ -f "${debs[0]}" ] || fail "cpack made no picksight_<version>_amd64.deb"
deb="${debs[0]}"
echo "package: $(basename "$deb"), $(stat -c %s "$deb") bytes," \
  "Installed-Size $(dpkg-deb -f "$deb" Installed-Size) KiB"
echo "Depends: $(dpkg-deb -f "$deb" Depends)"

# --- contents ---------------------------------------------------------------
dpkg-deb -c "$deb" >"$work/contents"
for path in ./usr/bin/picksight-video-server ./usr/bin/picksight-vision ./usr/bin/picksight-cam \
  ./usr/bin/picksight-calib ./usr/bin/picksight-robot ./usr/bin/picksight-keygen \
  ./usr/bin/picksight-web ./usr/lib/systemd/system/picksight-web.service ./etc/picksight/web.yaml \
  ./usr/lib/systemd/system/picksight-video-server.service \
  "./usr/lib/systemd/system/picksight-vision@.service" ./usr/lib/sysusers.d/picksight.conf \
  ./usr/lib/tmpfiles.d/picksight.conf ./usr/lib/udev/rules.d/99-picksight-u3v.rules \
  ./usr/lib/picksight/libpicksight_codecs.so \
  ./etc/picksight/video-server.yaml ./usr/share/doc/picksight/CAMERAS.md \
  ./etc/picksight/vision/cam0.yaml ./usr/share/doc/picksight/README.md \
  ./usr/share/doc/picksight/copyright ./usr/lib/python3/dist-packages/picksight/__init__.py \
  ./usr/lib/python3/dist-packages/picksight/robot.py \
  ./usr/lib/python3/dist-packages/picksight/picksight_pb2.py \
  ./usr/lib/python3/dist-packages/picksight/results_pb2.py; do
  awk '{print $6}' "$work/contents" | grep -qxF "$path" || fail "package lacks $path"
done
# Only the product: no test, benchmark or fuzzer binary.
if awk '{print $6}' "$work/contents" | grep -E '_test$|bench|fuzz|/tests/'; then
  fail "test, benchmark or fuzzer files in the package"
fi
# Everything root's, nothing group or world writable.
awk '$2 != "root/root" || $1 ~ /^.....w|^........w/' "$work/contents" >"$work/loose"
[ -s "$work/loose" ] && { cat "$work/loose" >&2; fail "files not root's or writable by others"; }
dpkg-deb -e "$deb" "$work/control"
diff <(sort "$work/control/conffiles") \
  <(printf '%s\n' /etc/picksight/video-server.yaml /etc/picksight/vision/cam0.yaml \
     /etc/picksight/web.yaml | sort) ||
  fail "conffiles are not the three example files"
echo "contents: $(grep -c '^-' "$work/contents") files; conffiles: $(tr '\n' ' ' <"$work/control/conffiles")"

# --- install ----------------------------------------------------------------
installed=1
touch "$marker"
dpkg -i "$deb" >"$work/dpkg-i.log" 2>&1 || { cat "$work/dpkg-i.log" >&2; fail "dpkg -i"; }
getent passwd picksight >/dev/null || fail "no picksight user after install"
id -nG picksight | tr ' ' '\n' | grep -qx video || fail "picksight is not in group video"
[ "$(stat -c '%U %a' /var/lib/picksight)" = "picksight 750" ] ||
  fail "/var/lib/picksight is $(stat -c '%U %a' /var/lib/picksight), not picksight 750"

# The web HMI's certificate and first admin, made by postinst: the key
# readable by the service's group only, the password by root only.
tls=/etc/picksight/tls
[ "$(stat -c '%U:%G %a' "$tls/web.key")" = "root:picksight 640" ] ||
  fail "$tls/web.key is $(stat -c '%U:%G %a' "$tls/web.key"), not root:picksight 640"
openssl x509 -noout -in "$tls/web.crt" -ext subjectAltName | grep -q 'IP Address:127.0.0.1' ||
  fail "$tls/web.crt does not name 127.0.0.1"
[ "$(stat -c '%U %a' /etc/picksight/web-admin-password)" = "root 600" ] ||
  fail "/etc/picksight/web-admin-password is not root's alone"
[ "$(stat -c '%U %a' /var/lib/picksight-web/users.json)" = "picksight 600" ] ||
  fail "/var/lib/picksight-web/users.json is not picksight's alone"
grep -q 'argon2id' /var/lib/picksight-web/users.json || fail "users.json holds no argon2id hash"
admin_password="$(cat /etc/picksight/web-admin-password)"
[ "${#admin_password}" = 20 ] || fail "the first admin's password is not 20 characters"
grep -qF "$admin_password" /var/lib/picksight-web/users.json && fail "users.json holds the password"
made="$(sha256sum "$tls/web.crt" "$tls/web.key" /etc/picksight/web-admin-password \
          /var/lib/picksight-web/users.json)"
echo "web HMI: $(openssl x509 -noout -subject -in "$tls/web.crt"), first admin's password in" \
  "/etc/picksight/web-admin-password"

# The installed units, at their real paths, with their real ExecStart.
out="$(systemd-analyze verify --man=no picksight-video-server.service \
         picksight-vision@cam0.service 2>&1)" || fail "systemd-analyze verify: $out"
[ -z "$out" ] || fail "systemd-analyze verify on the installed units: $out"
echo "systemd-analyze verify: the installed units are clean"

# An upgrade (here the same version again) keeps an edited conffile and
# runs postinst's upgrade branch.
echo "# edited on this cell" >>/etc/picksight/vision/cam0.yaml
dpkg -i "$deb" >"$work/dpkg-i2.log" 2>&1 || { cat "$work/dpkg-i2.log" >&2; fail "dpkg -i over itself"; }
grep -q '^# edited on this cell$' /etc/picksight/vision/cam0.yaml ||
  fail "reinstalling lost the edit of a conffile"
[ "$(sha256sum "$tls/web.crt" "$tls/web.key" /etc/picksight/web-admin-password \
      /var/lib/picksight-web/users.json)" = "$made" ] ||
  fail "reinstalling made a new certificate or admin"

# Starts a unit's ExecStart (instance %i = cam0, %S = /var/lib) as its
# User=, with extra arguments; its stdout goes to $work/<name>.out.
start_unit() {
  local unit="$1" name="$2"
  shift 2
  local exec_start
  exec_start="$(sed -n 's/^ExecStart=//p' "/usr/lib/systemd/system/$unit")"
  exec_start="${exec_start//%i/cam0}"
  exec_start="${exec_start//%S//var/lib}"
  # shellcheck disable=SC2086 # ExecStart is split into words as systemd does
  (cd / && exec setpriv --reuid=picksight --regid=picksight --init-groups --no-new-privs \
    -- $exec_start "$@") >"$work/$name.out" 2>"$work/$name.err" &
  pids+=("$!")
  echo "$!" >>"$marker"
}

# Waits until $work/<name>.out has a line starting with `prefix `; prints
# the rest of it.
wait_line() {
  local name="$1" prefix="$2" deadline=$((SECONDS + 30))
  while [ "$SECONDS" -lt "$deadline" ]; do
    local line
    line="$(grep -m1 "^$prefix " "$work/$name.out" 2>/dev/null)" && { echo "${line#"$prefix "}"; return 0; }
    sleep 0.1
  done
  cat "$work/$name.err" >&2
  return 1
}

start_unit picksight-video-server.service video-server \
  --frames 'tcp://127.0.0.1:*' --control 'tcp://127.0.0.1:*'
frames="$(wait_line video-server frames)" || fail "the installed video server did not start"
control="$(wait_line video-server control)" || fail "the installed video server did not start"

# The unit's StateDirectory=picksight/%i, as systemd would make it.
install -d -o picksight -g picksight -m 0750 /var/lib/picksight/cam0
start_unit picksight-vision@.service vision \
  --frames "$frames" --control "$control" --robot-port 0 --bind 127.0.0.1
port="$(wait_line vision robot)" || fail "the installed vision app did not start"
# The web HMI as its unit runs it (web.yaml: HTTPS with the package's
# certificate, a redirecting plain port), on free ports.
start_unit picksight-web.service web --listen 127.0.0.1:0 --http-redirect 127.0.0.1:0
web_url="$(wait_line web web)" || fail "the installed web HMI did not start"
redirect_url="$(wait_line web redirect)" || fail "the installed web HMI has no redirect port"
[[ "$web_url" == https://* ]] || fail "the installed web HMI serves $web_url, not HTTPS"
for pid in "${pids[@]}"; do
  [ "$(stat -c %U "/proc/$pid")" = picksight ] || fail "process $pid does not run as picksight"
done
# A client that verifies the certificate logs in with the first password.
headers="$(curl -sS --cacert "$tls/web.crt" -o /dev/null -D - -H 'Content-Type: application/json' \
             -H 'X-PickSight: 1' -d "{\"user\":\"admin\",\"password\":\"$admin_password\"}" \
             "$web_url/api/login")" || fail "curl --cacert $tls/web.crt $web_url/api/login failed"
grep -qiE '^HTTP/1.1 200' <<<"$headers" || fail "the first admin's login: $headers"
grep -qiE '^set-cookie: picksight_session=.*; Secure' <<<"$headers" ||
  fail "the session cookie is not Secure: $headers"
redirect="$(curl -sS -o /dev/null -w '%{http_code} %{redirect_url}' "$redirect_url/static/app.js")"
[ "$redirect" = "301 $web_url/static/app.js" ] || fail "the plain port answered '$redirect'"
echo "web HMI: $web_url (verified against $tls/web.crt), admin logged in; $redirect_url -> 301"
grep -q '"action":"login"' /var/lib/picksight-web/audit.jsonl || fail "the login is not in the audit trail"


# The packaged robot client, as an integrator would use it.
reply="$(/usr/bin/picksight-robot --port "$port" --timeout 30 'LOCATE 1')" ||
  fail "picksight-robot LOCATE 1 failed: '$reply'"
echo "LOCATE 1 -> $reply"
[[ "$reply" == "OK "* ]] || fail "LOCATE replied '$reply'"
# Image files through the installed codecs module (/usr/lib/picksight, which
# no program links: docs/ARCHITECTURE.md): a snapshot written as PNG by the
# packaged camera tool, read back by an offline LOCATE.
snap_out="$(/usr/bin/picksight-cam --control "$control" snap cam0 "$work/snap.png" 2>&1)" ||
  fail "picksight-cam snap: $snap_out"
offline="$(/usr/bin/picksight-vision locate --data-dir "$work/offline" "$work/snap.png" 2>&1)" ||
  fail "picksight-vision locate on the snapshot: $offline"
[[ "$offline" == "OK "* ]] || fail "the offline LOCATE of the snapshot replied '$offline'"
echo "snapshot through /usr/lib/picksight/libpicksight_codecs.so, offline LOCATE -> ${offline%% *} ${offline#OK }" | cut -c1-100

# The packaged Python client with Debian's python3, from no build tree: the
# installed module, and a request through it (its bytecode, written as root,
# must go with the package at purge).
py="$(cd / && env -u PYTHONPATH -u PYTHONDONTWRITEBYTECODE /usr/bin/python3 -c '
import sys, picksight
with picksight.RobotClient(port=int(sys.argv[1]), timeout=30) as robot:
    print(picksight.__file__, robot.request("STATUS")[0].split("=")[0])' "$port" 2>&1)" ||
  fail "import picksight with Debian's python3: $py"
[ "$py" = "/usr/lib/python3/dist-packages/picksight/__init__.py frame" ] ||
  fail "the Python client: '$py'"
echo "python3: import picksight -> $py"
# The bytecode python3 wrote there as root, which the purge must take away.
[ -d /usr/lib/python3/dist-packages/picksight/__pycache__ ] ||
  fail "python3 left no bytecode beside the client"

for pid in "${pids[@]}"; do kill -TERM "$pid"; done
for pid in "${pids[@]}"; do wait "$pid" || fail "a service exited with status $? on SIGTERM"; done
pids=()

# --- purge ------------------------------------------------------------------
dpkg-query -L picksight >"$work/owned"
dpkg --purge picksight >"$work/dpkg-purge.log" 2>&1 || { cat "$work/dpkg-purge.log" >&2; fail "dpkg --purge"; }
installed=0
rm -f "$marker"
left=()
while IFS= read -r path; do
  # Shared directories (/usr/bin, /etc...) stay; the package's own go.
  [ -e "$path" ] && ! [ -d "$path" ] && left+=("$path")
done <"$work/owned"
for dir in /etc/picksight /var/lib/picksight /usr/share/doc/picksight; do
  [ -e "$dir" ] && left+=("$dir")
done
if [ "${#left[@]}" -gt 0 ]; then
  printf '  %s\n' "${left[@]}" >&2
  fail "dpkg --purge left files behind"
fi
# Where a package's files go (not the whole disk: container images of the
# package may be stored under /var/lib).
stray="$(find /etc /usr/bin /usr/lib/systemd /usr/lib/sysusers.d /usr/lib/tmpfiles.d /usr/lib/udev \
           /usr/share/doc /var/lib/dpkg/info /usr/lib/python3/dist-packages -name '*picksight*' \
           -print 2>/dev/null
         find /var/lib -maxdepth 1 -name '*picksight*' -print)"
[ -n "$stray" ] && { printf '%s\n' "$stray" >&2; fail "files named picksight left after purge"; }
echo "purged: nothing left; the picksight user stays ($(getent passwd picksight | cut -d: -f1,3,6))"
echo "PASS"
