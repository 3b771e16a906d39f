#!/usr/bin/env bash
# Builds the Debian bookworm base image for rths without any image registry:
# debootstrap (minbase) from Debian's mirror into a temporary directory, then `podman import`.
# Usage: docker/make_base_image.sh [IMAGE_NAME]   (default: localhost/rths-bookworm-base:latest)
# Needs root, debootstrap and podman. Skips the work when the image already exists
# (set RTHS_REBUILD_BASE=1 to force). The temporary root file system is always removed.
set -euo pipefail
image="${1:-localhost/rths-bookworm-base:latest}"
mirror="${RTHS_DEBIAN_MIRROR:-http://deb.debian.org/debian}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$here/containers.conf}"

if [[ "${RTHS_REBUILD_BASE:-0}" != 1 ]] && podman image exists "$image"; then
  echo "base image $image exists (RTHS_REBUILD_BASE=1 rebuilds it)"
  exit 0
fi
for tool in debootstrap podman tar; do
  command -v "$tool" >/dev/null || { echo "missing tool: $tool (apt-get install $tool)" >&2; exit 3; }
done

rootfs="$(mktemp -d /var/tmp/rths-rootfs.XXXXXX)"
trap 'rm -rf --one-file-system "$rootfs"' EXIT
debootstrap --variant=minbase bookworm "$rootfs" "$mirror"
# Keep the image small: package lists and caches are fetched again by the Dockerfile's apt-get.
rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
tar -C "$rootfs" --numeric-owner -c . | podman import \
  --change 'CMD ["/bin/bash"]' --change 'ENV LANG=C.UTF-8' - "$image"
echo "imported $image"
