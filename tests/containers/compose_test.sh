#!/usr/bin/env bash
# The three services of docker/compose.yaml (coordinator, substructure node, actuator emulator),
# each in its own container, run with podman-compose from an image made of this build's binaries
# (docker/make_test_image.sh); the lag measured across the containers is checked against the lag
# the nodes injected. Everything runs inside a private network namespace: nothing is attached to
# the host's network. Exits 77 (ctest: skipped) with the reason printed where podman cannot run.
#   usage: compose_test.sh BUILD_DIR
set -uo pipefail
build="$(cd "$1" && pwd)"
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
export CONTAINERS_CONF="$repo/docker/containers.conf"
image="localhost/rths-test:latest"
tag="rths-compose-$$"
delay=0.007  # s each way on the actuator link (docker/compose.yaml's default)

skip() { echo "SKIPPED: $*"; exit 77; }
fail() { echo "FAILED: $*"; exit 1; }
step() { echo "== [$(( $(date +%s) - t0 )) s] $*"; }
t0=$(date +%s)

[ "$(id -u)" -eq 0 ] || skip "rootful podman and a network namespace need root"
for tool in podman runc podman-compose debootstrap ip nsenter; do
  command -v "$tool" >/dev/null || skip "$tool is not installed (apt-get install podman runc podman-compose debootstrap iproute2)"
done
podman info >/dev/null 2>&1 || skip "podman cannot run here: $(podman info 2>&1 | tail -1)"

out="$(mktemp -d /tmp/rths-compose.XXXXXX)"
# The run secret the compose file hands every service, from this shell's environment.
RTHS_RUN_SECRET=$(openssl rand -hex 32)
export RTHS_RUN_SECRET
# podman-compose inside the namespace, with the compose file's RTHS_* settings for this test.
compose=(nsenter --net="/run/netns/$tag" env RTHS_IMAGE="$image" RTHS_OUT="$out" RTHS_DOMAIN=152
         RTHS_DURATION=0.5 RTHS_ACTUATOR_ONE_WAY_DELAY=$delay
         podman-compose -p "$tag" -f "$repo/docker/compose.yaml")
cleanup() {
  "${compose[@]}" down -t 1 >/dev/null 2>&1
  ip netns del "$tag" 2>/dev/null
  rm -rf "$out"
}
trap cleanup EXIT

step "test image from $build (debootstrap + runtime packages + the binaries, no compiler)"
"$repo/docker/make_test_image.sh" "$build" "$image"
code=$?
[ $code -eq 0 ] || { [ $code -eq 3 ] && skip "the test image cannot be made here"; fail "make_test_image.sh exit $code"; }
podman run --rm --network none "$image" /opt/rths/bin/rths-coordinator --help >/dev/null 2>&1 ||
  skip "podman cannot start a container here: $(podman run --rm --network none "$image" true 2>&1 | tail -1)"

ip netns add "$tag" || skip "network namespaces are not permitted here"
ip -n "$tag" link set lo up
step "podman-compose up: coordinator, substructure, actuator (0.5 s of El Centro, lockstep, $delay s each way on the actuator link)"
timeout 180 "${compose[@]}" up --abort-on-container-exit --exit-code-from coordinator > "$out/compose.log" 2>&1
status=$?
grep -E "coordinator|round trip|FAIL|error" "$out/compose.log" | tail -8
[ $status -eq 0 ] || { tail -30 "$out/compose.log"; fail "podman-compose up exit $status"; }
[ -s "$out/record.pb" ] || fail "the coordinator wrote no record"

step "measured lag across containers against the injected lag"
check=$("$build/cli/rths" sites --check-record "$out/record.pb" --expect-steps 500) || fail "record check: $check"
echo "$check"
read -r injected measured < <(echo "$check" | awk '/node 2:/ {print $5, $10}')
echo "actuator link: injected median $injected ms, measured round trip median $measured ms"
awk -v i="$injected" -v m="$measured" -v d="$delay" 'BEGIN {
  expected = 2 * d * 1e3
  if (i < expected - 1 || i > expected + 1) { print "injected " i " ms, expected " expected " ms"; exit 1 }
  if (m < i) { print "measured below injected"; exit 1 }
  if (m > i + 10) { print "measured exceeds injected by more than 10 ms"; exit 1 }
}' || fail "lag check"
step "PASSED: measured round trip $measured ms >= injected $injected ms (+ transport < 10 ms) across three containers"
