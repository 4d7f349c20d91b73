/* SPDX-License-Identifier: AGPL-3.0-or-later
 * Thin C glue between hmc.h and the JavaScript module (web/src/index.mjs).
 * Why a glue at all: JavaScript reads wasm memory by byte offset, and the
 * offsets of hmc_stream_info's members are a detail of the C compiler; these
 * getters keep the JS side independent of struct layout. Everything else the
 * module calls (create, feed, finish, level_*) is hmc.h itself. */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "hmc/hmc.h"

/* Header and progress as doubles, in this order: header_ready, kind, bits,
 * origin x, y, z, step, declared_levels, bytes_consumed, complete_levels,
 * ended, truncated, then declared_points coarsest first (declared_levels
 * values). `out` must hold 12 + 64 doubles. Returns an hmc_status. */
int hmc_web_stream_info(const hmc_decoder *dec, double *out) {
  hmc_stream_info info;
  const hmc_status s = hmc_decoder_stream_info(dec, &info);
  if (s != HMC_OK) return (int)s;
  out[0] = info.header_ready;
  out[1] = info.kind;
  out[2] = info.bits;
  out[3] = info.origin[0];
  out[4] = info.origin[1];
  out[5] = info.origin[2];
  out[6] = info.step;
  out[7] = info.declared_levels;
  out[8] = (double)info.bytes_consumed;
  out[9] = info.complete_levels;
  out[10] = info.ended;
  out[11] = info.truncated;
  for (uint32_t i = 0; i < info.declared_levels && i < HMC_MAX_LEVELS; ++i) out[12 + i] = (double)info.declared_points[i];
  return HMC_OK;
}

/* A level's figures as doubles: lod, point_count, triangle_count,
 * tetrahedron_count, stream_bytes. */
int hmc_web_level_info(const hmc_decoder *dec, size_t index, double *out) {
  hmc_level_info info;
  const hmc_status s = hmc_decoder_level_info(dec, index, &info);
  if (s != HMC_OK) return (int)s;
  out[0] = info.lod;
  out[1] = (double)info.point_count;
  out[2] = (double)info.triangle_count;
  out[3] = (double)info.tetrahedron_count;
  out[4] = (double)info.stream_bytes;
  return HMC_OK;
}

/* A number as C's printf("%.17g") writes it, which the canonical dump's
 * header.json prescribes (spec/conformance.md 2.1): musl's printf is exact,
 * so JavaScript need not reimplement the rounding. `out` holds 32 bytes. */
void hmc_web_format_g17(double v, char *out) { snprintf(out, 32, "%.17g", v); }

/* 64-bit limits travel from JavaScript as doubles (exact below 2^53). */
int hmc_web_set_limits(hmc_decoder *dec, double max_points, uint32_t max_levels, double max_bytes, double max_memory) {
  hmc_status s = hmc_decoder_set_limits(dec, (uint64_t)max_points, max_levels, (uint64_t)max_bytes);
  if (s == HMC_OK && max_memory > 0) s = hmc_decoder_set_memory_limit(dec, (uint64_t)max_memory);
  return (int)s;
}

/* The default limits, so that JS options can leave any of them unset. */
void hmc_web_default_limits(double *out) {
  hmc_decoder *dec = hmc_decoder_create(NULL);
  uint64_t p = 0, b = 0;
  uint32_t l = 0;
  hmc_decoder_get_limits(dec, &p, &l, &b);
  out[0] = (double)p;
  out[1] = l;
  out[2] = (double)b;
  out[3] = (double)hmc_decoder_memory_limit(dec);
  hmc_decoder_destroy(dec);
}
