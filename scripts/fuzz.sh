#!/usr/bin/env bash
# Runs every cargo-fuzz target of fuzz/ for a bounded time, one after the
# other, and prints the executions of each.
#
#   scripts/fuzz.sh [SECONDS_PER_TARGET] [TARGET...]     (default: 60 s, all targets)
#
# Needs cargo-fuzz (`cargo install cargo-fuzz`). cargo-fuzz passes nightly-only
# flags (-Zsanitizer=address); on a stable toolchain RUSTC_BOOTSTRAP=1 lets
# them through. Seeds are read from fuzz/corpus/<target> (kept in git); new
# inputs go to fuzz/corpus-work/<target> (ignored). A crash, timeout or
# oversized allocation is saved in fuzz/artifacts/<target>/ and makes the
# script exit non-zero: fix the loader, then copy the input to
# tests/data/fuzz/<target>/ so tests/fuzz_regressions.rs keeps checking it.
set -euo pipefail

cd "$(dirname "$0")/.."
seconds="${1:-60}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(ply off obj scene mitsuba serialized gltf)
fi
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -eq 0 ]; then
    echo "usage: $0 [SECONDS_PER_TARGET] [TARGET...]" >&2
    exit 2
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "error: cargo-fuzz is not installed: run 'cargo install cargo-fuzz'" >&2
    exit 2
fi
export RUSTC_BOOTSTRAP=1

cargo fuzz build -O

status=0
summary=()
for t in "${targets[@]}"; do
    mkdir -p "fuzz/corpus-work/$t" "fuzz/artifacts/$t"
    log="fuzz/artifacts/$t/last-run.log"
    echo "== fuzzing $t for ${seconds} s (log: $log)"
    set +e
    # -max_len: meshes and scenes that matter are small; 64 KiB leaves room
    # for gzip streams and long headers. -timeout: one input may take 5 s at
    # most (a hang). -rss_limit_mb / -malloc_limit_mb: a big allocation is a bug.
    cargo fuzz run -O "$t" "fuzz/corpus-work/$t" "fuzz/corpus/$t" -- \
        -max_total_time="$seconds" -max_len=65536 -timeout=5 \
        -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1 \
        >"$log" 2>&1
    code=$?
    set -e
    execs=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *\([0-9]*\).*/\1/p' "$log" | tail -1)
    if [ "$code" -ne 0 ]; then
        status=1
        verdict="FAILED (exit $code): see $log and fuzz/artifacts/$t/"
        grep -E "^(==[0-9]+==ERROR|SUMMARY|artifact_prefix|Test unit written)" "$log" | head -5 || true
    else
        verdict="ok"
    fi
    line=$(printf '%-6s %6s s  %12s executions  %8s exec/s  %s' "$t" "$seconds" "${execs:-?}" "${rate:-?}" "$verdict")
    echo "$line"
    summary+=("$line")
done
echo
echo "== summary"
printf '%s\n' "${summary[@]}"
exit "$status"
