#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# Set up, build, and run the whole test suite (what CI runs): CTest, then
# the WebAssembly decoder's conformance run and the headless browser test
# (scripts/test_web.sh). With CI=true, also the sanitizer build and the
# fuzz smoke test (scripts/sanitize.sh).
set -eu
. "$(dirname "$0")/setup.sh"
JOBS=$(nproc 2>/dev/null || echo 2)
ctest --test-dir "$HMC_BUILD" --output-on-failure -j "$JOBS"
"$HMC_ROOT/scripts/test_web.sh"
if [ "${CI:-}" = true ]; then
  "$HMC_ROOT/scripts/sanitize.sh"
fi
