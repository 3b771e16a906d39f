#!/usr/bin/env bash
# The test image from the build's own binaries, with no compiler inside and no image registry:
#   base  debootstrap --variant=minbase bookworm including the runtime packages the node programs
#         load (found with ldd + dpkg -S on this host), then `podman import`; tagged by the hash of
#         the package list and reused while it is unchanged;
#   image the base + the three node programs, configs/, data/ and the compose study, `podman build
#         --network none`; labelled with the hash of its inputs, rebuilt only when they changed.
# Minutes from nothing, seconds after a code change. Downloaded packages stay in
# /var/cache/rths-debootstrap.
#   usage: docker/make_test_image.sh BUILD_DIR [IMAGE]   (default localhost/rths-test:latest)
# Needs root, debootstrap and podman. Exit 3 when a tool or a program is missing.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/.." && pwd)"
build="$(cd "${1:?usage: $0 BUILD_DIR [IMAGE]}" && pwd)"
image="${2:-localhost/rths-test:latest}"
mirror="${RTHS_DEBIAN_MIRROR:-http://deb.debian.org/debian}"
cache="${RTHS_DEBOOTSTRAP_CACHE:-/var/cache/rths-debootstrap}"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$here/containers.conf}"

for tool in debootstrap podman tar ldd dpkg; do
  command -v "$tool" >/dev/null || { echo "missing tool: $tool (apt-get install $tool)" >&2; exit 3; }
done
programs=("$build/coordinator/rths-coordinator" "$build/substructure_nodes/rths-substructure-node"
          "$build/actuator_emulator/rths-actuator-emulator")
for program in "${programs[@]}"; do
  [ -x "$program" ] || { echo "missing program: $program (build it first)" >&2; exit 3; }
done

# The Debian packages that own the shared libraries the programs load.
packages=$(for program in "${programs[@]}"; do ldd "$program"; done \
  | awk '$2 == "=>" && $3 ~ /^\// {print $3}' | sort -u \
  | while read -r library; do
      dpkg -S "$library" 2>/dev/null || dpkg -S "$(readlink -f "$library")" 2>/dev/null || dpkg -S "${library#/usr}"
    done | cut -d: -f1 | sort -u | paste -sd, -)
# The base (debootstrap + runtime packages) is its own image, keyed by the package list, so a
# rebuild after a code change only copies the programs in (seconds).
base_key=$( (echo "$packages"; sed -n '/^# base-image-recipe/,/^# end-base-image-recipe/p' "${BASH_SOURCE[0]}") | sha256sum | cut -c1-16)
base="localhost/rths-test-base:$base_key"
key=$( (echo "$base_key"; sha256sum "${programs[@]}" "$here/compose_study.textproto";
        find "$repo/configs" "$repo/data" -type f -print0 | sort -z | xargs -0 sha256sum) | sha256sum | cut -c1-16)
if podman image exists "$image" &&
   [ "$(podman image inspect --format '{{index .Config.Labels "rths.inputs"}}' "$image" 2>/dev/null)" = "$key" ]; then
  echo "image $image is up to date (inputs $key)"
  exit 0
fi

start=$(date +%s)
work="$(mktemp -d /var/tmp/rths-test-image.XXXXXX)"
trap 'rm -rf --one-file-system "$work"' EXIT
if ! podman image exists "$base"; then
  # base-image-recipe
  mkdir -p "$cache" "$work/rootfs"
  echo "debootstrap minbase bookworm + $packages (package cache $cache)"
  # Two stages, so dpkg in the second runs with force-unsafe-io (no fsync per file: much faster).
  debootstrap --foreign --variant=minbase --cache-dir="$cache" --include="$packages" bookworm "$work/rootfs" "$mirror" \
    > "$work/debootstrap.log" 2>&1 || { tail -20 "$work/debootstrap.log"; exit 3; }
  mkdir -p "$work/rootfs/etc/dpkg/dpkg.cfg.d"
  echo force-unsafe-io > "$work/rootfs/etc/dpkg/dpkg.cfg.d/unsafe-io"
  chroot "$work/rootfs" /debootstrap/debootstrap --second-stage > "$work/debootstrap.log" 2>&1 ||
    { tail -20 "$work/debootstrap.log"; exit 3; }
  rm -rf "$work/rootfs"/var/lib/apt/lists/* "$work/rootfs"/var/cache/apt/archives/*.deb
  tar -C "$work/rootfs" --numeric-owner -c . | podman import --quiet \
    --change 'ENV PATH=/opt/rths/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin' \
    --change 'ENV LANG=C.UTF-8' --change 'WORKDIR /work' --change 'CMD ["/bin/bash"]' - "$base" >/dev/null
  # end-base-image-recipe
  echo "base image $base in $(( $(date +%s) - start )) s"
fi

# The programs and configs on top of the base: no compiler, no network.
mkdir -p "$work/context/bin" "$work/context/docker"
cp "${programs[@]}" "$work/context/bin/"
cp -r "$repo/configs" "$work/context/configs"
cp -r "$repo/data" "$work/context/data"
cp "$here/compose_study.textproto" "$work/context/docker/"
cat > "$work/context/Containerfile" <<CONTAINERFILE
FROM $base
COPY bin /opt/rths/bin
COPY configs /opt/rths/configs
COPY data /opt/rths/data
COPY docker /opt/rths/docker
LABEL rths.inputs=$key
CONTAINERFILE
podman build --quiet --network none -t "$image" "$work/context" >/dev/null
echo "image $image (inputs $key) in $(( $(date +%s) - start )) s"
