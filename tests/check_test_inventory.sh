#!/usr/bin/env bash
# Checks that CTest runs every Catch test case of a build exactly once, by name.
#
# CTest learns the test cases from `<binary> --list-test-names-only` through
# catch_discover_tests, which keeps them in a CMake list: a ';' in a name
# splits it into two entries that each match no test case, and a test that
# matches nothing used to exit 0 and count as a pass. This fails when
#   - a test binary holds a case that has no CTest entry of the same name,
#   - a CTest entry of a test binary names no case of that binary,
#   - the number of cases and of entries differ,
#   - a name holds a character that CMake or Catch's test-spec parser reads
#     as syntax (see below).
# With `per-binary` (a build with PICKSIGHT_TEST_PER_BINARY), each test
# binary has exactly one CTest entry, of its own name, that runs every case.
# Usage: tests/check_test_inventory.sh <build dir> [per-case|per-binary]
set -euo pipefail

build="${1:?usage: check_test_inventory.sh <build dir> [per-case|per-binary]}"
mode="${2:-per-case}"
case "$mode" in per-case|per-binary) ;; *) echo "unknown mode $mode" >&2; exit 2 ;; esac
tests_dir="$build/tests"
[ -d "$tests_dir" ] || { echo "no $tests_dir" >&2; exit 2; }

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# Every Catch case, as "<binary>:<name>" (the TEST_PREFIX the CMake files use).
: >"$work/cases"
binaries=0
while IFS= read -r -d '' binary; do
  name="$(basename "$binary")"
  binaries=$((binaries + 1))
  # Catch exits with the number of cases listed: not an error.
  listed="$("$binary" --list-test-names-only)" || true
  [ -n "$listed" ] || { echo "FAIL: $name lists no test case" >&2; exit 1; }
  # Kept for the per-binary check below: under the sanitizers each listing
  # is a process start of a second or more.
  printf '%s\n' "$listed" | LC_ALL=C sort >"$work/listed.$name"
  printf '%s\n' "$listed" | sed "s|^|$name:|" >>"$work/cases"
done < <(find "$tests_dir" -maxdepth 1 -type f -executable -print0)
[ "$binaries" -gt 0 ] || { echo "FAIL: no test binary in $tests_dir" >&2; exit 1; }

# Every CTest entry, by name; only those of a test binary (prefix "<binary>:",
# or the binary's name itself per binary).
(cd "$build" && ctest -N) | sed -n 's/^ *Test *#[0-9]*: //p' >"$work/all_entries"
find "$tests_dir" -maxdepth 1 -type f -executable -printf '%f\n' >"$work/binaries"
awk -F: 'NR == FNR { binary[$0] = 1; next } ($1 in binary)' "$work/binaries" \
  "$work/all_entries" >"$work/entries"
if [ "$mode" = per-binary ]; then
  # What CTest must hold then: each binary's name, once.
  cut -d: -f1 "$work/cases" | sort -u >"$work/expected"
else
  cp "$work/cases" "$work/expected"
fi

export LC_ALL=C
sort "$work/expected" >"$work/cases.sorted"
sort "$work/entries" >"$work/entries.sorted"
status=0

# ';' splits a name in CMake's list; '\\' and a leading '~', '#' or '*' (or
# a trailing '*') are test-spec syntax that catch_discover_tests does not
# escape (it escapes ',' '[' ']', so those run; new names avoid them anyway).
bad="$(cut -d: -f2- "$work/cases" | grep -E '[;\\]|^[~#*]|[*]$' || true)"
if [ -n "$bad" ]; then
  echo "FAIL: test names with characters CTest or Catch read as syntax:" >&2
  printf '%s\n' "$bad" | sed 's/^/  /' >&2
  status=1
fi

missing="$(comm -23 "$work/cases.sorted" "$work/entries.sorted")"
if [ -n "$missing" ]; then
  echo "FAIL: test cases CTest does not run:" >&2
  printf '%s\n' "$missing" | sed 's/^/  /' >&2
  status=1
fi
phantom="$(comm -13 "$work/cases.sorted" "$work/entries.sorted")"
if [ -n "$phantom" ]; then
  echo "FAIL: CTest entries that name no test case (they run nothing):" >&2
  printf '%s\n' "$phantom" | sed 's/^/  /' >&2
  status=1
fi

# Per binary, the entry's own arguments must run the cases it stands for:
# every case the binary lists (never a hidden one: any test spec, even one
# that only leaves cases out, makes Catch 2 select hidden cases too), less
# the [accuracy] and [sweep] ones where the build leaves them out
# (PICKSIGHT_TEST_SKIP_ACCURACY).
if [ "$mode" = per-binary ]; then
  (cd "$build" && ctest --show-only=json-v1) >"$work/ctest.json"
  /usr/bin/python3 - "$work/ctest.json" "$tests_dir" >"$work/commands" <<'PY'
import json, os, sys
tests_dir = os.path.realpath(sys.argv[2])
for test in json.load(open(sys.argv[1]))["tests"]:
    command = test.get("command") or []
    if command and os.path.dirname(os.path.realpath(command[0])) == tests_dir:
        print("\x1f".join(command))
PY
  # One line an entry, its command's words apart by the unit separator.
  while IFS=$'\x1f' read -r -a command; do
    binary="${command[0]}"
    name="$(basename "$binary")"
    cp "$work/listed.$name" "$work/want"
    if [ "${#command[@]}" -gt 1 ]; then
      "$binary" "[accuracy],[sweep]" --list-test-names-only | sort >"$work/left_out" || true
      comm -23 "$work/want" "$work/left_out" >"$work/want.kept"
      mv "$work/want.kept" "$work/want"
    fi
    "$binary" "${command[@]:1}" --list-test-names-only | sort >"$work/runs" || true
    if ! cmp -s "$work/want" "$work/runs"; then
      echo "FAIL: CTest's $name (${command[*]:1}) runs other cases than it stands for:" >&2
      diff "$work/want" "$work/runs" | sed 's/^/  /' >&2 || true
      status=1
    fi
  done <"$work/commands"
fi

cases=$(wc -l <"$work/cases")
expected=$(wc -l <"$work/expected")
entries=$(wc -l <"$work/entries")
if [ "$expected" -ne "$entries" ]; then
  echo "FAIL: $cases test cases in $binaries binaries, $entries CTest entries ($mode)" >&2
  status=1
fi
[ "$status" -eq 0 ] && echo "test inventory: $cases test cases in $binaries binaries, one CTest entry each ($mode)"
exit "$status"
