#!/usr/bin/env bash
# Containerised integration test of rths (not in the default test suite: it builds an image).
#   docker/run_container_test.sh            # from anywhere; needs root, podman, runc, debootstrap
# Steps: base image (debootstrap + podman import, once), the rths image (docker/Dockerfile), then
# the three services of docker/compose.yaml on a podman network -- all inside a private network
# namespace, so nothing is attached to the host's network -- and the record is checked.
# Environment: RTHS_SKIP_IMAGE_BUILD=1 reuses localhost/rths:latest; RTHS_KEEP_OUTPUT=1 keeps the
# output folder; ACTUATOR_ONE_WAY_DELAY (default 0.010 s) is injected each way on the actuator link.
# Exit: 0 pass, 1 the run or the check failed, 3 environment (tool missing, no permission).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/.." && pwd)"
export CONTAINERS_CONF="${CONTAINERS_CONF:-$here/containers.conf}"
image="localhost/rths:latest"
delay="${ACTUATOR_ONE_WAY_DELAY:-0.010}"
for tool in podman runc debootstrap ip; do
  command -v "$tool" >/dev/null || { echo "missing tool: $tool (apt-get install podman runc debootstrap iproute2)" >&2; exit 3; }
done
[[ "$(id -u)" == 0 ]] || { echo "needs root (network namespace and rootful podman)" >&2; exit 3; }

"$here/make_base_image.sh"
if [[ "${RTHS_SKIP_IMAGE_BUILD:-0}" != 1 ]]; then
  # Host network for the build only: apt-get reaches Debian's mirror; no bridge is created.
  podman build --network host -f "$here/Dockerfile" --ignorefile "$here/dockerignore" -t "$image" "$repo"
fi

tag="rths-ctest-$$"
out="$(mktemp -d /tmp/rths-ctest.XXXXXX)"
# nsenter, not `ip netns exec`: the latter remounts /sys, hiding the cgroup mount runc needs.
in_ns() { nsenter --net="/run/netns/$tag" "$@"; }
cleanup() {
  set +e
  for service in coordinator substructure actuator; do
    in_ns podman rm -f -t 2 "$tag-$service" >/dev/null 2>&1
  done
  in_ns podman network rm -f "$tag" >/dev/null 2>&1
  ip netns del "$tag" 2>/dev/null
  if [[ "${RTHS_KEEP_OUTPUT:-0}" == 1 ]]; then echo "output kept in $out"; else rm -rf "$out"; fi
}
trap cleanup EXIT
ip netns add "$tag" || { echo "network namespaces are not permitted here" >&2; exit 3; }
ip -n "$tag" link set lo up

in_ns podman network create --internal "$tag" >/dev/null
dds="CYCLONEDDS_URI=file:///opt/rths/configs/dds_netns_containers.xml"
# The run secret reaches each container from this shell's environment (`-e NAME` with no value),
# never on a command line.
RTHS_RUN_SECRET=$(openssl rand -hex 32)
export RTHS_RUN_SECRET
start_node() {  # service, program, node id
  in_ns podman run -d --name "$tag-$1" --network "$tag" --network-alias "$1" --hostname "$1" \
    -e "$dds" -e RTHS_RUN_SECRET "$image" "$2" --node-id "$3" --domain 140 --run-id "$tag" >/dev/null
}
start_node substructure rths-substructure-node 1
start_node actuator rths-actuator-emulator 2

echo "running the coordinator (lockstep, 1 s of El Centro, $delay s each way on the actuator link)"
set +e
timeout 300 nsenter --net="/run/netns/$tag" podman run --name "$tag-coordinator" --network "$tag" \
  --network-alias coordinator --hostname coordinator -e "$dds" -e RTHS_RUN_SECRET -v "$out:/out" "$image" bash -c "
    sed -e 's/@CLOCK@/LOCKSTEP/' -e 's/@DURATION@/1/' -e 's/@DOMAIN@/140/' \
        -e 's/@ACTUATOR_ONE_WAY_DELAY@/$delay/g' -e 's/@ACTUATOR_JITTER@/0/g' \
        -e 's/@SUBSTRUCTURE_ONE_WAY_DELAY@/0/g' \
        /opt/rths/docker/compose_study.textproto > /tmp/study.textproto &&
    rths-coordinator --config /tmp/study.textproto --run-id $tag --record /out/record.pb" \
  | tee "$out/coordinator.log"
status=${PIPESTATUS[0]}
set -e
for service in substructure actuator; do
  in_ns podman logs "$tag-$service" > "$out/$service.log" 2>&1 || true
done
if [[ $status != 0 ]]; then
  echo "FAIL: coordinator exit $status"; tail -20 "$out/substructure.log" "$out/actuator.log"; exit 1
fi
[[ -s "$out/record.pb" ]] || { echo "FAIL: no record written"; exit 1; }

# The record, checked on the host side of the image: steps, footer, and the injected lag.
in_ns podman run --rm --network none -v "$out:/out" "$image" \
  rths sites --check-record /out/record.pb --expect-steps 1000 --expect-injected "$(awk "BEGIN{print 2*$delay}")" \
  && echo "PASS: containerised run across three services, record checked"
