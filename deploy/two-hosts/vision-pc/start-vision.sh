#!/usr/bin/env bash
# Starts the vision app of one instance on the vision PC from a build tree,
# as picksight-vision@<instance>.service does on an installed one: its
# configuration is <instance>.yaml beside this script, its state
# <state root>/<instance>.
# Usage: start-vision.sh <instance> [state root (/var/lib/picksight)]
# PICKSIGHT_BIN names the directory of picksight-vision (default: PATH).
set -euo pipefail
instance="${1:?usage: start-vision.sh <instance> [state root]}"
root="${2:-/var/lib/picksight}"
here="$(cd "$(dirname "$0")" && pwd)"
config="$here/$instance.yaml"
[ -r "$config" ] || { echo "start-vision: no $config" >&2; exit 2; }
mkdir -p "$root/$instance"
vision="picksight-vision"
[ -n "${PICKSIGHT_BIN:-}" ] && vision="$PICKSIGHT_BIN/picksight-vision"
exec "$vision" --config "$config" --data-dir "$root/$instance"
