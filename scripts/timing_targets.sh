#!/usr/bin/env bash
# The timing job (issue 65 item 4): the tight real-time bounds the suite relaxes on a shared
# machine, held to their targets. Run it on a quiet machine (nothing else building or running)
# or a 16-core one, after a build:
#   scripts/timing_targets.sh [BUILD_DIR]        (default: build)
# It sets RTHS_TIMING_TARGETS=1, under which the doc-controller real-time tests hold the frame
# interval to 5 % of dt, the applied answer age's p99 to answer lag + 1 ms + the loop's round
# trip, and no lost or late frame, and refuse to pass a run that completed with deadline misses;
# with them it runs the suite's other real-time runs (DDS pacing, the emulator's own stall, the
# coordinator's real-time tests). Each test runs alone (ctest -j1), so the job's own tests do
# not load the machine they judge.
# Exit: 0 when every test passed; 1 when one failed, or skipped (a skip here means the machine
# was not quiet enough to judge timing: the job failed its purpose), naming each.
set -euo pipefail
build=${1:-build}
tests='DocControllerTest\.RealTime|DocControllerTest\.AFloodFromAnotherPort|DdsRun\.RealTime|Faults\.TheEmulatorsOwnStall|Coordinator.*RealTime'
log=$(mktemp)
trap 'rm -f "$log"' EXIT
export RTHS_TIMING_TARGETS=1
status=0
ctest --test-dir "$build" -R "$tests" -j1 --output-on-failure 2>&1 | tee "$log" || status=1
skipped=$(grep -E '\*\*\*Skipped|Not Run' "$log" || true)
if [[ -n "$skipped" ]]; then
  echo "timing_targets: skipped, so not judged (the machine was not quiet enough):" >&2
  echo "$skipped" >&2
  status=1
fi
if ! grep -qE '^[0-9]+% tests passed' "$log"; then
  echo "timing_targets: no test matched '$tests' in $build" >&2
  status=1
fi
exit "$status"
