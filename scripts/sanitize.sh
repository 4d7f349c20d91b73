#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# Sanitizer and fuzz step; scripts/test.sh runs it when CI=true.
#
#  1. build-asan/: the whole project built with clang++ (g++ when clang is
#     missing) and -DHMC_SANITIZE=address,undefined; runs the whole CTest
#     suite, fuzz corpus replays included.
#  2. build-fuzz/: when clang has libFuzzer, the fuzz targets
#     (-DHMC_BUILD_FUZZ=ON); runs each for HMC_FUZZ_SECONDS seconds
#     (default 20) from its seed corpus and regression inputs.
#
# Any sanitizer report, failing test, fuzz crash, leak or slow input
# (over 5 s) fails the script; a fuzz failure's input is left in
# build-fuzz/smoke/artifacts/<target>/ (add it to fuzz/regressions/<target>/
# once fixed, see fuzz/README.md). Installs clang and libclang-rt-14-dev
# when missing, like scripts/setup.sh does for the rest.
set -eu
HMC_SETUP_NO_BUILD=1
. "$(dirname "$0")/setup.sh"
hmc_install_missing clang libclang-rt-14-dev || echo "sanitize: cannot install clang; using g++" >&2

ASAN_BUILD=${HMC_ASAN_BUILD:-$HMC_ROOT/build-asan}
FUZZ_BUILD=${HMC_FUZZ_BUILD:-$HMC_ROOT/build-fuzz}
FUZZ_SECONDS=${HMC_FUZZ_SECONDS:-20}
TARGETS="container huffman base_layer decode roundtrip"

if command -v clang++ >/dev/null 2>&1 && command -v clang >/dev/null 2>&1; then
  CC_SAN=clang CXX_SAN=clang++
else
  CC_SAN=gcc CXX_SAN=g++
fi
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

start=$(date +%s)
echo "sanitize: $CXX_SAN, address,undefined -> $ASAN_BUILD"
cmake -S "$HMC_ROOT" -B "$ASAN_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER="$CC_SAN" -DCMAKE_CXX_COMPILER="$CXX_SAN" -DHMC_SANITIZE=address,undefined >/dev/null
cmake --build "$ASAN_BUILD" -j "$JOBS"
ctest --test-dir "$ASAN_BUILD" --output-on-failure -j "$JOBS"
echo "sanitize: sanitizer build and tests took $(( $(date +%s) - start )) s"

# libFuzzer: clang only, and only if it links.
probe=$(mktemp -d)
trap 'rm -rf "$probe"' EXIT INT TERM
printf 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }\n' >"$probe/p.cpp"
if [ "$CXX_SAN" != clang++ ] || ! clang++ -fsanitize=fuzzer "$probe/p.cpp" -o "$probe/p" 2>/dev/null; then
  echo "sanitize: clang with libFuzzer is not available; fuzz targets skipped"
  exit 0
fi

fstart=$(date +%s)
cmake -S "$HMC_ROOT" -B "$FUZZ_BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DHMC_BUILD_FUZZ=ON -DHMC_BUILD_TESTS=OFF -DHMC_BUILD_TOOLS=OFF >/dev/null
fuzz_bins=""
for t in $TARGETS; do fuzz_bins="$fuzz_bins fuzz_$t"; done
# shellcheck disable=SC2086
cmake --build "$FUZZ_BUILD" -j "$JOBS" --target $fuzz_bins

SMOKE=$FUZZ_BUILD/smoke
rm -rf "$SMOKE"
for t in $TARGETS; do
  mkdir -p "$SMOKE/corpus/$t" "$SMOKE/artifacts/$t"
  seeds="$HMC_ROOT/fuzz/corpus/$t"
  [ -d "$HMC_ROOT/fuzz/regressions/$t" ] && seeds="$seeds $HMC_ROOT/fuzz/regressions/$t"
  # shellcheck disable=SC2086
  if "$FUZZ_BUILD/fuzz/fuzz_$t" -max_total_time="$FUZZ_SECONDS" -timeout=5 -rss_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$SMOKE/artifacts/$t/" "$SMOKE/corpus/$t" $seeds \
       >"$SMOKE/$t.log" 2>&1; then
    echo "sanitize: fuzz_$t: $(grep -o 'number_of_executed_units: *[0-9]*' "$SMOKE/$t.log" | grep -o '[0-9]*$') runs, $(grep -E '^#[0-9]+[[:space:]]+DONE' "$SMOKE/$t.log" | grep -o 'cov: [0-9]* ft: [0-9]*'), no failure"
  else
    tail -n 60 "$SMOKE/$t.log" >&2
    echo "sanitize: fuzz_$t FAILED; input in $SMOKE/artifacts/$t/, log in $SMOKE/$t.log" >&2
    exit 1
  fi
done
echo "sanitize: fuzz build and smoke took $(( $(date +%s) - fstart )) s; total $(( $(date +%s) - start )) s"
