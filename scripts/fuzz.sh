#!/usr/bin/env bash
# Fuzzes rths's parsers of outside input (fuzz/targets.h) with libFuzzer, AddressSanitizer
# (with LeakSanitizer) and UBSan:
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET [TARGET...]]     default: 75 s each, every target
# Builds build-fuzz/ with clang (-DRTHS_FUZZ=ON; the normal g++ build never needs clang), then runs
# each target for the given time, seeded with fuzz/corpus/<target>/ (kept small, committed); new
# inputs go to build-fuzz/corpus/<target>/. A crash, leak, sanitizer report, an input that takes
# more than 10 s (a hang) or 2 GB stops that target and is saved as build-fuzz/findings/<target>/
# crash-* (or leak-*, timeout-*, oom-*). Each finding becomes a regression test in the normal suite.
# Exit: 0 nothing found, 1 something found (listed at the end), 3 clang or the build missing.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-75}"
shift || true
all=(study_config deployment_config sites_config at2_motion column_motion daq_export run_record
     envelope_payload record_flips study_values controller_frame)
targets=("$@")
((${#targets[@]})) || targets=("${all[@]}")

if ! command -v clang++ >/dev/null || ! clang++ -fsanitize=fuzzer -x c++ -o /dev/null - \
     <<<'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' \
     2>/dev/null; then
  echo "fuzz.sh: needs clang with libFuzzer: apt-get install clang libclang-rt-dev" >&2
  exit 3
fi

build=build-fuzz
sanitize="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja "${launcher[@]}" -DRTHS_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DCMAKE_C_FLAGS="$sanitize -fsanitize=fuzzer-no-link" \
  -DCMAKE_CXX_FLAGS="$sanitize -fsanitize=fuzzer-no-link" \
  -DCMAKE_EXE_LINKER_FLAGS="$sanitize" >/dev/null
cmake --build "$build" -j"$(nproc)" --target "${targets[@]/#/fuzz_}"

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:symbolize=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
found=()
summary=()
for t in "${targets[@]}"; do
  work="$build/corpus/$t"
  findings="$build/findings/$t"
  mkdir -p "$work" "$findings"
  log="$build/findings/$t.log"
  echo "== $t: ${seconds} s"
  status=0
  (cd "$build/findings" && "../fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 \
     -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$t/" \
     "../corpus/$t" "../../fuzz/corpus/$t") >"$log" 2>&1 || status=$?
  runs=$(grep -m1 -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  inputs=$(find "$work" -type f | wc -l)
  if ((status != 0)) || compgen -G "$findings/*" >/dev/null; then
    found+=("$t")
    summary+=("$t: FOUND (exit $status) after $runs runs; see $log and $findings/")
    tail -40 "$log"
  else
    summary+=("$t: $runs runs in $seconds s, no crash, leak or hang; corpus $inputs inputs")
  fi
done
echo "== summary"
printf '%s\n' "${summary[@]}"
if ((${#found[@]})); then
  echo "fuzz.sh: findings in: ${found[*]}" >&2
  exit 1
fi
