#!/usr/bin/env bash
# Starts the vision app of one instance on the vision PC with the options of
# <instance>.args beside this script and its state in <state root>/<instance>.
# Usage: start-vision.sh <instance> [state root (/var/lib/picksight)]
# PICKSIGHT_BIN names the directory of picksight-vision (default: PATH).
set -euo pipefail
instance="${1:?usage: start-vision.sh <instance> [state root]}"
root="${2:-/var/lib/picksight}"
here="$(cd "$(dirname "$0")" && pwd)"
args_file="$here/$instance.args"
[ -r "$args_file" ] || { echo "start-vision: no $args_file" >&2; exit 2; }
mkdir -p "$root/$instance"
# Each non-comment line is "--option value".
args=()
while read -r option value; do
  case "$option" in ''|'#'*) continue ;; esac
  args+=("$option")
  [ -n "$value" ] && args+=("$value")
done <"$args_file"
vision="picksight-vision"
[ -n "${PICKSIGHT_BIN:-}" ] && vision="$PICKSIGHT_BIN/picksight-vision"
exec "$vision" "${args[@]}" --data-dir "$root/$instance"
