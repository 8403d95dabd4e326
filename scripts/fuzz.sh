#!/usr/bin/env bash
# A short real libFuzzer run of the fuzz/ targets on the STABLE toolchain
# (no nightly, no cargo-fuzz): plain cargo with the coverage flags cargo-fuzz
# passes (sancov-module: inline 8-bit counters, PC table, comparison tracing),
# release with debug assertions and overflow checks, and libfuzzer-sys's
# libFuzzer (needs a C++ compiler). AddressSanitizer is left out (it needs a
# -Z flag); the targets are safe Rust, whose bugs show as panics, which
# libfuzzer-sys turns into crashes.
#
# 1. The `canary` target (a planted bug behind an 8-byte comparison) must
#    crash within FUZZ_CANARY_SECONDS, or the instrumentation is broken and
#    the run fails.
# 2. `frames`, `job` and `points` each run FUZZ_SECONDS (default 45), and
#    `plan`, `link_rx`, `candump`, `machine_file` and `web` FUZZ_SHORT_SECONDS
#    (default half of it: they are smaller surfaces, and CI's whole fuzz
#    step must stay short), from their committed corpus and
#    fuzz/regressions/, with fuzz/TARGET.dict when there is one; any crash
#    fails, leaving the input in $OUT/crashes/. New inputs go to $OUT, never
#    into the corpus.
#
# Output: ${CARGO_TARGET_DIR:-target}/fuzz/ (its own build: the flags differ).
# FUZZ_BUILD_ONLY=1: the build alone.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
SECONDS_PER_TARGET=${FUZZ_SECONDS:-45}
SHORT_SECONDS=${FUZZ_SHORT_SECONDS:-$((SECONDS_PER_TARGET / 2))}
CANARY_SECONDS=${FUZZ_CANARY_SECONDS:-60}
DIR="${CARGO_TARGET_DIR:-$ROOT/target}/fuzz"
OUT="$DIR/run"
step() { printf '\n==> fuzz: %s\n' "$*"; }

if ! command -v c++ >/dev/null; then
    step "g++ (libFuzzer is C++)"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends g++ >/dev/null \
        || { apt-get update -qq && DEBIAN_FRONTEND=noninteractive \
            apt-get install -y -qq --no-install-recommends g++ >/dev/null; }
fi

step "build (stable, sanitizer coverage)"
host=$(rustc -vV | sed -n 's/^host: //p')
# --target: the flags then reach only the target code, not build scripts
# and proc-macros (as cargo-fuzz does it).
RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks" \
    CARGO_TARGET_DIR="$DIR" nice cargo build --manifest-path fuzz/Cargo.toml --release --locked \
    --target "$host" --bins
BIN="$DIR/$host/release"
# Build only (test.sh builds beside the tests, then runs them here).
[ -n "${FUZZ_BUILD_ONLY:-}" ] && exit 0

rm -rf "$OUT"
mkdir -p "$OUT/crashes"
# Runs target $1 for $2 s on the corpus directories that follow. New inputs
# go to the first directory, the scratch one: the committed corpus is read only.
fuzz() {
    local t=$1 secs=$2
    shift 2
    local opts=()
    [ -f "$ROOT/fuzz/$t.dict" ] && opts=(-dict="$ROOT/fuzz/$t.dict")
    mkdir -p "$OUT/corpus-$t"
    "$BIN/$t" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
        -artifact_prefix="$OUT/crashes/$t-" "${opts[@]}" "$OUT/corpus-$t" "$@" \
        > "$OUT/$t.log" 2>&1
}

step "canary: the planted bug must be found (${CANARY_SECONDS} s at most)"
if fuzz canary "$CANARY_SECONDS"; then
    tail -5 "$OUT/canary.log"
    echo "fuzz: the canary was not found: coverage instrumentation is not working" >&2
    exit 1
fi
if ! grep -q "canary: the fuzzer found the planted bug" "$OUT/canary.log"; then
    tail -20 "$OUT/canary.log"
    echo "fuzz: the canary run failed for another reason" >&2
    exit 1
fi
grep -E "^#[0-9]+|Done|panicked" "$OUT/canary.log" | tail -2
rm -f "$OUT"/crashes/canary-*

# Two targets at a time: libFuzzer runs on one core, and each target still
# gets its full time.
JOBS=${FUZZ_JOBS:-2}
targets=(frames job points plan link_rx candump machine_file web)
for t in "${targets[@]}"; do
    case $t in
        frames | job | points) secs=$SECONDS_PER_TARGET ;;
        *) secs=$SHORT_SECONDS ;;
    esac
    while [ "$(jobs -rp | wc -l)" -ge "$JOBS" ]; do wait -n || true; done
    (
        if fuzz "$t" "$secs" "$ROOT/fuzz/corpus/$t" "$ROOT/fuzz/regressions/$t"; then
            echo 0 > "$OUT/$t.status"
        else
            echo 1 > "$OUT/$t.status"
        fi
    ) &
done
wait

status=0
for t in "${targets[@]}"; do
    step "$t: from the committed corpus"
    if [ "$(cat "$OUT/$t.status" 2>/dev/null)" = 0 ]; then
        grep -E "^stat::(number_of_executed_units|new_units_added)|^Done" "$OUT/$t.log" || true
    else
        status=1
        tail -40 "$OUT/$t.log"
        echo "fuzz: $t crashed; input kept in $OUT/crashes/ (add it to fuzz/regressions/$t/ with the fix)" >&2
    fi
done
exit "$status"
