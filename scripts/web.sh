#!/usr/bin/env bash
# SPDX-License-Identifier: AGPL-3.0-or-later
# Builds the WebAssembly decoder (web/dist/hmc.mjs + hmc.wasm) with Debian's
# emscripten, installing it (and Node.js) when missing; --serve then serves
# web/ with a plain static file server.
#
#   scripts/web.sh            build into web/dist
#   scripts/web.sh --serve    build, then serve web/ on http://localhost:8000/ (PORT=...)
#
# The decoder-only library is configured without the encoder, TetGen, zlib or
# threads (HMC_BUILD_ENCODER=OFF ...): the native exact Delaunay backend and
# libhmc's own CRC-32 give the same output, bit for bit.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${HMC_WASM_BUILD:-$ROOT/build-wasm}
JOBS=${JOBS:-2}
serve=0
for a in "$@"; do
  case "$a" in
    --serve) serve=1 ;;
    *) echo "usage: scripts/web.sh [--serve]" >&2; exit 1 ;;
  esac
done

need=()
command -v emcc >/dev/null || need+=(emscripten)
command -v node >/dev/null || need+=(nodejs)
command -v npm >/dev/null || need+=(npm)
command -v cmake >/dev/null || need+=(cmake)
command -v ninja >/dev/null || need+=(ninja-build)
if ((${#need[@]})); then
  SUDO=; [ "$(id -u)" = 0 ] || SUDO=sudo
  $SUDO apt-get update
  $SUDO apt-get install -y "${need[@]}"
fi

# Debian's emscripten ships a frozen cache (system headers) under
# /usr/share/emscripten/cache; the system libraries (libc, libc++) are built
# into a writable copy on first use, from the sources the package ships.
export EM_CACHE=${EM_CACHE:-/tmp/emcache}
if [ ! -e "$EM_CACHE/sysroot_install.stamp" ] && [ -d /usr/share/emscripten/cache ]; then
  mkdir -p "$EM_CACHE"
  cp -a /usr/share/emscripten/cache/. "$EM_CACHE/"
fi
export EM_FROZEN_CACHE=0
# emscripten's JS optimizer needs acorn, which Debian installs (node-acorn)
# where a Node.js not from Debian does not look.
export NODE_PATH=/usr/share/nodejs:/usr/lib/nodejs${NODE_PATH:+:$NODE_PATH}
mkdir -p "$EM_CACHE" "$ROOT/web/dist"

# -fexceptions: libhmc reports stream errors internally by exceptions that
# the C API turns into status values; emscripten's default (-fignore-exceptions)
# would abort instead.
WASM_CXXFLAGS="-fexceptions"
emcmake cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DHMC_BUILD_ENCODER=OFF -DHMC_WITH_TETGEN=OFF -DHMC_WITH_ZLIB=OFF -DHMC_NO_THREADS=ON \
  -DCMAKE_CXX_FLAGS="$WASM_CXXFLAGS" >/dev/null
nice cmake --build "$BUILD" --target hmc -j "$JOBS"

# The exported surface: hmc.h's decoder calls and web/src/glue.c.
exports=(hmc_decoder_create hmc_decoder_destroy hmc_decoder_feed hmc_decoder_finish hmc_decoder_decode
  hmc_decoder_status hmc_decoder_message hmc_decoder_level_count hmc_decoder_level_positions
  hmc_decoder_level_points hmc_decoder_level_triangles hmc_decoder_level_tetrahedra
  hmc_decoder_set_reconstruct hmc_decoder_set_rebuild_coarser_levels hmc_decoder_set_finest_level
  hmc_decoder_set_error_order hmc_status_string hmc_version_string hmc_free
  hmc_web_stream_info hmc_web_level_info hmc_web_format_g17 hmc_web_set_limits hmc_web_default_limits
  malloc free)
list=$(printf '"_%s",' "${exports[@]}")
# -O3, no FMA contraction (normative arithmetic, as the native build); the
# memory grows on demand up to wasm32's 4 GiB.
nice emcc -O3 -fexceptions -ffp-contract=off -fno-fast-math -I"$ROOT/libhmc/include" "$ROOT/web/src/glue.c" "$BUILD/libhmc/libhmc.a" \
  -o "$ROOT/web/dist/hmc.mjs" \
  -sMODULARIZE=1 -sEXPORT_ES6=1 -sEXPORT_NAME=createHmcModule -sENVIRONMENT=web,worker,node \
  -sALLOW_MEMORY_GROWTH=1 -sMAXIMUM_MEMORY=4GB -sUSE_ZLIB=0 -sDISABLE_EXCEPTION_CATCHING=0 \
  -sEXPORTED_FUNCTIONS="[${list%,}]" -sEXPORTED_RUNTIME_METHODS='["UTF8ToString","HEAPU8","HEAPU32","HEAPF64"]'
ls -l "$ROOT/web/dist"

if ((serve)); then
  cd "$ROOT/web"
  echo "serving $ROOT/web on http://localhost:${PORT:-8000}/"
  exec python3 -m http.server "${PORT:-8000}"
fi
