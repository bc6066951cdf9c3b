#!/usr/bin/env bash
# Builds the PickSight container images without any registry:
#   1. a Debian 12 root filesystem made by mmdebstrap from the package
#      archive, with the libraries the build's binaries link (found with ldd
#      and dpkg -S) and a `picksight` system user,
#   2. imported as localhost/picksight-base:bookworm (podman import),
#   3. the two images built on it with `podman build --pull=never`:
#      localhost/picksight-video-server and localhost/picksight-vision.
# Usage: deploy/containers/build.sh [build dir (build)] [Debian mirror]
# Needs root (or a user with subuids for podman), mmdebstrap and podman.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
build="$(cd "${1:-build}" && pwd)"
mirror="${2:-http://deb.debian.org/debian}"
bin="$build/bin"
base=localhost/picksight-base:bookworm

for tool in mmdebstrap podman ldd dpkg; do
  command -v "$tool" >/dev/null || { echo "containers: $tool missing (apt-get install mmdebstrap podman)" >&2; exit 2; }
done
binaries=(picksight-video-server picksight-cam picksight-vision picksight-robot)
for b in "${binaries[@]}"; do
  [ -x "$bin/$b" ] || { echo "containers: $bin/$b not built" >&2; exit 2; }
done

work="$(mktemp -d /tmp/picksight-containers-XXXXXX)"
trap 'rm -rf "$work"' EXIT

# The Debian packages that hold the libraries the binaries load, in one
# dpkg query (usrmerge: dpkg knows a file under /lib or /usr/lib, so both
# spellings of each path are asked; the unknown ones are ignored).
packages_of() {
  for b in "$@"; do ldd "$bin/$b"; done |
    awk '$2 == "=>" && $3 ~ /^\// { print $3 }' | sort -u |
    while read -r lib; do
      real="$(readlink -f "$lib")"
      printf '%s\n' "$lib" "$real" "${real#/usr}" "/usr${lib#/usr}"
    done | sort -u | xargs dpkg -S 2>/dev/null | cut -d: -f1 | sort -u
}
mapfile -t packages < <(packages_of "${binaries[@]}")
echo "containers: runtime packages: ${packages[*]}"
include="$(IFS=,; echo "${packages[*]}")"

# Step 1: the root filesystem. Only the listed packages and Debian's
# required set (minbase); no recommends. The user owns the state directory.
mmdebstrap --variant=minbase --include="$include" \
  --customize-hook='chroot "$1" useradd --system --home-dir /var/lib/picksight --no-create-home --groups video --shell /usr/sbin/nologin picksight' \
  --customize-hook='mkdir -p "$1/var/lib/picksight" "$1/etc/picksight" && chroot "$1" chown picksight:picksight /var/lib/picksight' \
  --customize-hook='rm -rf "$1"/var/cache/apt/* "$1"/var/lib/apt/lists/*' \
  bookworm "$work/rootfs.tar" "$mirror" </dev/null

# Step 2: the base image.
podman import --change 'CMD ["/bin/bash"]' "$work/rootfs.tar" "$base"

# Step 3: the images, from a context holding only what they copy.
mkdir -p "$work/context/bin"
for b in "${binaries[@]}"; do cp "$bin/$b" "$work/context/bin/"; done
cp "$here/video-server.yaml" "$work/context/"
for image in video-server vision; do
  podman build --pull=never -f "$here/Containerfile.$image" -t "localhost/picksight-$image:latest" \
    "$work/context"
done
podman images --filter reference='localhost/picksight-*'
