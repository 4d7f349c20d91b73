#!/bin/sh
# SPDX-License-Identifier: AGPL-3.0-or-later
# The browser half of the test suite (scripts/test.sh runs it after CTest):
#  1. builds the WebAssembly decoder (scripts/web.sh: emscripten, Node.js);
#  2. runs the conformance suite's full profile through `node web/cli.mjs`
#     (every positive vector bit-exact, every negative case its error name),
#     then a tiled model (web/test/tiles.mjs: merged dumps equal hmc dec's,
#     region queries over HTTP range requests);
#  3. installs the viewer's and the test's npm packages (pinned by their
#     lock files) and the system chromium, and runs web/test/browser.mjs:
#     headless Chromium opens the viewer on generated 4-level streams and
#     checks what it draws against the native decoder, then hostile streams.
# Needs the native build ($HMC_BUILD/bin/hmc). Installs what is missing.
set -eu
HMC_SETUP_NO_BUILD=1
. "$(dirname "$0")/setup.sh"
# Node.js and npm by command: a Node.js from elsewhere (NodeSource's
# package carries npm) conflicts with Debian's npm package.
web_packages="emscripten chromium"
command -v node >/dev/null 2>&1 || web_packages="$web_packages nodejs"
command -v npm >/dev/null 2>&1 || web_packages="$web_packages npm"
# shellcheck disable=SC2086
hmc_install_missing $web_packages
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT INT TERM
# quiet NAME CMD...: runs CMD into $LOG; prints its last lines, or all of
# it and fails when CMD fails.
quiet() {
  name=$1
  shift
  if "$@" >"$LOG" 2>&1; then tail -n 2 "$LOG"; else cat "$LOG" >&2; echo "test_web: $name FAILED" >&2; exit 1; fi
}
start=$(date +%s)
quiet "WebAssembly build" "$HMC_ROOT/scripts/web.sh"
echo "test_web: WebAssembly built in $(( $(date +%s) - start )) s"
t=$(date +%s)
quiet "conformance through web/cli.mjs" python3 "$HMC_ROOT/conformance/run.py" --profile full \
  --decoder "node $HMC_ROOT/web/cli.mjs dec {in} --canonical {outdir}"
echo "test_web: conformance (full profile, WebAssembly in Node) took $(( $(date +%s) - t )) s"
t=$(date +%s)
quiet "tiled models through web/cli.mjs" node "$HMC_ROOT/web/test/tiles.mjs" --hmc "$HMC_BUILD/bin/hmc"
echo "test_web: tiled models (WebAssembly in Node against hmc dec) took $(( $(date +%s) - t )) s"
t=$(date +%s)
(cd "$HMC_ROOT/web/viewer" && npm ci --no-audit --no-fund --silent)
(cd "$HMC_ROOT/web/test" && npm ci --no-audit --no-fund --silent)
quiet "browser test" node "$HMC_ROOT/web/test/browser.mjs" --hmc "$HMC_BUILD/bin/hmc"
echo "test_web: browser test took $(( $(date +%s) - t )) s"
