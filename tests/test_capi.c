/* SPDX-License-Identifier: AGPL-3.0-or-later */
/* The C API (hmc/hmc.h), from plain C99: handles, encoding a generated
 * surface and volume, whole-buffer and streaming decoding, errors and the
 * permanent failed state, the allocator hook, limits and misuse. */
#include <hmc/hmc.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int g_checks = 0, g_failures = 0;

#define CHECK(cond)                                                      \
  do {                                                                   \
    ++g_checks;                                                          \
    if (!(cond)) {                                                       \
      ++g_failures;                                                      \
      fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, #cond); \
    }                                                                    \
  } while (0)

#define CHECK_STATUS(expr, want)                                                         \
  do {                                                                                   \
    hmc_status got_ = (expr);                                                            \
    ++g_checks;                                                                          \
    if (got_ != (want)) {                                                                \
      ++g_failures;                                                                      \
      fprintf(stderr, "%s:%d: %s returned %s, expected %s\n", __FILE__, __LINE__, #expr, \
              hmc_status_string(got_), hmc_status_string(want));                         \
    }                                                                                    \
  } while (0)

/* ------------------------------------------------------------ test data */

/* A torus on an nu x nv grid: 3*nu*nv coordinates and 2*nu*nv triangles. */
typedef struct mesh {
  double *xyz;
  size_t points;
  uint32_t *tris;
  size_t triangles;
} mesh;

static mesh make_torus(unsigned nu, unsigned nv) {
  mesh m;
  unsigned i, j;
  const double pi = 3.14159265358979323846;
  m.points = (size_t)nu * nv;
  m.triangles = 2 * m.points;
  m.xyz = malloc(3 * m.points * sizeof(double));
  m.tris = malloc(3 * m.triangles * sizeof(uint32_t));
  for (i = 0; i < nu; ++i)
    for (j = 0; j < nv; ++j) {
      const double u = 2 * pi * i / nu, v = 2 * pi * j / nv;
      double *p = m.xyz + 3 * ((size_t)i * nv + j);
      p[0] = (1.0 + 0.35 * cos(v)) * cos(u);
      p[1] = (1.0 + 0.35 * cos(v)) * sin(u);
      p[2] = 0.35 * sin(v);
    }
  for (i = 0; i < nu; ++i)
    for (j = 0; j < nv; ++j) {
      const uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv,
                     d = i * nv + (j + 1) % nv;
      uint32_t *t = m.tris + 6 * ((size_t)i * nv + j);
      t[0] = a, t[1] = b, t[2] = c;
      t[3] = a, t[4] = c, t[5] = d;
    }
  return m;
}

/* Points inside the unit ball, deterministic. */
static double *make_ball(size_t n) {
  double *xyz = malloc(3 * n * sizeof(double));
  unsigned long long s = 88172645463325252ull;
  size_t k = 0;
  while (k < n) {
    double p[3];
    int a;
    for (a = 0; a < 3; ++a) {
      s ^= s << 13, s ^= s >> 7, s ^= s << 17;
      p[a] = (double)(s >> 11) / 9007199254740992.0 * 2.0 - 1.0;
    }
    if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > 1.0) continue;
    memcpy(xyz + 3 * k++, p, sizeof p);
  }
  return xyz;
}

static uint8_t *encode_torus_with(unsigned nu, unsigned nv, int levels, int fast_decode, size_t *size) {
  mesh m = make_torus(nu, nv);
  hmc_encoder *enc = hmc_encoder_create(NULL);
  hmc_encode_options o;
  uint8_t *bytes = NULL;
  hmc_encode_options_init(&o);
  o.levels = levels;
  o.fast_decode = fast_decode;
  o.boundary_mode = HMC_BOUNDARY_LINEAR;
  CHECK(enc != NULL);
  CHECK_STATUS(hmc_encoder_set_options(enc, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(enc, m.xyz, m.points, m.tris, m.triangles, NULL, 0, &bytes, size), HMC_OK);
  hmc_encoder_destroy(enc);
  free(m.xyz);
  free(m.tris);
  return bytes;
}

static uint8_t *encode_torus(unsigned nu, unsigned nv, int levels, size_t *size) {
  return encode_torus_with(nu, nv, levels, 0, size);
}

/* ------------------------------------------------------------ the tests */

static int less3(const uint32_t *a, const uint32_t *b) {
  if (a[0] != b[0]) return a[0] < b[0];
  if (a[1] != b[1]) return a[1] < b[1];
  return a[2] < b[2];
}

static void test_strings(void) {
  CHECK(strlen(hmc_version_string()) >= 5);
  CHECK(strcmp(hmc_status_string(HMC_OK), "ok") == 0);
  CHECK(strcmp(hmc_status_string(HMC_CRC_MISMATCH), "crc_mismatch") == 0);
  CHECK(strcmp(hmc_status_string(HMC_LIMIT_EXCEEDED), "limit_exceeded") == 0);
  CHECK(strcmp(hmc_status_string(HMC_INCOMPLETE), "incomplete") == 0);
  CHECK(strcmp(hmc_status_string((hmc_status)77), "unknown_status") == 0);
  CHECK(strlen(hmc_status_description(HMC_BAD_LAYER)) > 0);
  CHECK(strcmp(hmc_encoder_message(NULL), "") == 0);
  CHECK(strcmp(hmc_decoder_message(NULL), "") == 0);
}

static void test_handles(void) {
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_decoder *d = hmc_decoder_create(NULL);
  CHECK(e != NULL);
  CHECK(d != NULL);
  CHECK_STATUS(hmc_decoder_status(d), HMC_OK);
  CHECK(hmc_decoder_level_count(d) == 0);
  hmc_encoder_destroy(e);
  hmc_decoder_destroy(d);
  hmc_encoder_destroy(NULL);
  hmc_decoder_destroy(NULL);
  hmc_free(NULL, NULL);
}

static void test_encode_options(void) {
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_encode_options o;
  double xyz[3] = {0, 0, 0};
  uint32_t tri[3] = {0, 1, 5};
  uint8_t *out = (uint8_t *)1;
  size_t size = 99;
  hmc_encode_options_init(&o);
  CHECK(o.bits == 12 && o.levels == 1 && o.kind == HMC_KIND_AUTO && o.write_info == 1);
  CHECK(o.boundary_mode == HMC_BOUNDARY_LINEAR && o.fast_decode == 0);
  o.bits = 22;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_INVALID_ARGUMENT);
  CHECK(strlen(hmc_encoder_message(e)) > 0);
  hmc_encode_options_init(&o);
  CHECK(o.fidelity == HMC_FIDELITY_SHAPE);
  o.fidelity = HMC_FIDELITY_TOPOLOGY;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  o.fidelity = HMC_FIDELITY_TOPOLOGY + 1;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_INVALID_ARGUMENT);
  hmc_encode_options_init(&o);
  o.optimizer = 9;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_INVALID_ARGUMENT);
  o.optimizer = HMC_OPTIMIZER_GREEDY;
  o.removal_ratio = 0;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_set_options(e, NULL), HMC_INVALID_ARGUMENT);
  /* No points; an index out of range; a NaN; NULL arrays. */
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 0, NULL, 0, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  CHECK(out == NULL && size == 0);
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 1, tri, 1, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  xyz[1] = NAN;
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 1, NULL, 0, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_encode(e, NULL, 1, NULL, 0, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 1, NULL, 0, NULL, 0, NULL, &size), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_encode(NULL, xyz, 1, NULL, 0, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  hmc_encoder_destroy(e);
}

/* Notes of the last successful encode: four points make one level of the
 * two asked for; a failing encode clears them. */
static void test_encoder_notes(void) {
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_encode_options o;
  double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  uint8_t *out = NULL;
  size_t size = 0;
  CHECK(strcmp(hmc_encoder_notes(NULL), "") == 0);
  CHECK(strcmp(hmc_encoder_notes(e), "") == 0);
  hmc_encode_options_init(&o);
  o.levels = 2;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 4, NULL, 0, NULL, 0, &out, &size), HMC_OK);
  CHECK(strstr(hmc_encoder_notes(e), "1 of the 2 levels requested") != NULL);
  CHECK(strstr(hmc_encoder_notes(e), "it has 4 points\n") != NULL);
  hmc_free(NULL, out);
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 0, NULL, 0, NULL, 0, &out, &size), HMC_INVALID_ARGUMENT);
  CHECK(strcmp(hmc_encoder_notes(e), "") == 0);
  o.levels = 1;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, xyz, 4, NULL, 0, NULL, 0, &out, &size), HMC_OK);
  CHECK(strcmp(hmc_encoder_notes(e), "") == 0);
  hmc_free(NULL, out);
  hmc_encoder_destroy(e);
}

/* Threads: the same stream and the same levels, triangles included; out of
 * range or too late is refused. */
static void test_threads(void) {
  mesh m = make_torus(48, 20);
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_decoder *one = hmc_decoder_create(NULL), *two = hmc_decoder_create(NULL);
  hmc_encode_options o;
  uint8_t *bytes = NULL;
  size_t size = 0, ref_size = 0, k;
  uint8_t *ref = encode_torus(48, 20, 3, &ref_size);
  CHECK_STATUS(hmc_encoder_set_threads(NULL, 2), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_set_threads(e, 0), HMC_INVALID_ARGUMENT);
  CHECK(strstr(hmc_encoder_message(e), "threads") != NULL);
  CHECK_STATUS(hmc_encoder_set_threads(e, 65), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_set_threads(e, 2), HMC_OK);
  hmc_encode_options_init(&o); /* as encode_torus(): the setting survives set_options */
  o.levels = 3;
  o.boundary_mode = HMC_BOUNDARY_LINEAR;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, m.xyz, m.points, m.tris, m.triangles, NULL, 0, &bytes, &size), HMC_OK);
  CHECK(size == ref_size && memcmp(bytes, ref, size) == 0);

  CHECK_STATUS(hmc_decoder_set_threads(NULL, 2), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_threads(two, 0), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_threads(two, 65), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_threads(two, 2), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(one, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(two, bytes, size), HMC_OK);
  CHECK(hmc_decoder_level_count(one) == 3 && hmc_decoder_level_count(two) == 3);
  for (k = 0; k < 3; ++k) {
    uint32_t *t1 = NULL, *t2 = NULL;
    size_t n1 = 0, n2 = 0;
    CHECK_STATUS(hmc_decoder_level_triangles(one, k, &t1, &n1), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_triangles(two, k, &t2, &n2), HMC_OK);
    CHECK(n1 > 0 && n1 == n2 && memcmp(t1, t2, 3 * n1 * sizeof(uint32_t)) == 0);
    hmc_free(NULL, t1);
    hmc_free(NULL, t2);
  }
  CHECK_STATUS(hmc_decoder_set_threads(two, 1), HMC_INVALID_ARGUMENT); /* decoding has begun */
  hmc_free(NULL, bytes);
  hmc_free(NULL, ref);
  hmc_decoder_destroy(one);
  hmc_decoder_destroy(two);
  hmc_encoder_destroy(e);
  free(m.xyz);
  free(m.tris);
}

/* Preview levels: more levels, the coarsest a few percent, the finest the
 * same points as the 1-level stream's; a bad ratio is refused. */
static void test_preview(void) {
  mesh m = make_torus(80, 40);
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_decoder *plain = hmc_decoder_create(NULL), *prev = hmc_decoder_create(NULL);
  hmc_encode_options o;
  uint8_t *bytes = NULL, *one = NULL;
  size_t size = 0, one_size = 0, n = 0, n1 = 0;
  uint32_t *p = NULL, *p1 = NULL;
  hmc_level_info coarsest;
  CHECK_STATUS(hmc_encoder_set_preview_ratio(NULL, 0.04), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_set_preview_ratio(e, 1.0), HMC_INVALID_ARGUMENT);
  CHECK(strstr(hmc_encoder_message(e), "preview ratio") != NULL);
  CHECK_STATUS(hmc_encoder_set_preview_ratio(e, -0.5), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_encoder_encode(e, m.xyz, m.points, m.tris, m.triangles, NULL, 0, &one, &one_size), HMC_OK);
  CHECK_STATUS(hmc_encoder_set_preview_ratio(e, 0.04), HMC_OK);
  hmc_encode_options_init(&o); /* the setting survives set_options */
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, m.xyz, m.points, m.tris, m.triangles, NULL, 0, &bytes, &size), HMC_OK);
  CHECK(size > one_size);
  CHECK_STATUS(hmc_decoder_decode(plain, one, one_size), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(prev, bytes, size), HMC_OK);
  CHECK(hmc_decoder_level_count(plain) == 1 && hmc_decoder_level_count(prev) >= 3);
  CHECK_STATUS(hmc_decoder_level_info(prev, 0, &coarsest), HMC_OK);
  CHECK(coarsest.point_count > 0 && coarsest.point_count <= m.points / 25);
  CHECK_STATUS(hmc_decoder_level_points(plain, 0, &p1, &n1), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_points(prev, hmc_decoder_level_count(prev) - 1, &p, &n), HMC_OK);
  CHECK(n == n1 && n == m.points && memcmp(p, p1, 3 * n * sizeof(uint32_t)) == 0);
  hmc_free(NULL, p);
  hmc_free(NULL, p1);
  hmc_free(NULL, bytes);
  hmc_free(NULL, one);
  hmc_decoder_destroy(plain);
  hmc_decoder_destroy(prev);
  hmc_encoder_destroy(e);
  free(m.xyz);
  free(m.tris);
}

/* fast_decode: a larger stream with the same points. */
static void test_fast_decode(void) {
  size_t size = 0, fast_size = 0, count = 0, fast_count = 0;
  uint8_t *bytes = encode_torus(48, 20, 3, &size), *fast = encode_torus_with(48, 20, 3, 1, &fast_size);
  hmc_decoder *d = hmc_decoder_create(NULL), *f = hmc_decoder_create(NULL);
  uint32_t *pts = NULL, *fast_pts = NULL;
  CHECK(bytes != NULL && fast != NULL && fast_size > size);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(f, fast, fast_size), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_points(d, 2, &pts, &count), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_points(f, 2, &fast_pts, &fast_count), HMC_OK);
  CHECK(count == 48 * 20 && fast_count == count && memcmp(pts, fast_pts, 3 * count * sizeof *pts) == 0);
  free(pts);
  free(fast_pts);
  hmc_decoder_destroy(d);
  hmc_decoder_destroy(f);
  free(bytes);
  free(fast);
}

static void test_round_trip(void) {
  size_t size = 0, n = 0, count = 0, i;
  uint8_t *bytes = encode_torus(48, 20, 3, &size);
  hmc_decoder *d = hmc_decoder_create(NULL);
  hmc_stream_info info;
  hmc_level_info li;
  uint32_t *pts = NULL, *tris = NULL, *tets = NULL;
  double *xyz = NULL;
  CHECK(bytes != NULL && size > 100);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK(strcmp(hmc_decoder_message(d), "") == 0);
  n = hmc_decoder_level_count(d);
  CHECK(n == 3);
  CHECK_STATUS(hmc_decoder_stream_info(d, &info), HMC_OK);
  CHECK(info.header_ready && info.ended && !info.truncated);
  CHECK(info.kind == HMC_KIND_SURFACE);
  CHECK(info.bits == 12);
  CHECK(info.declared_levels == 3);
  CHECK(info.declared_points[2] == 48 * 20);
  CHECK(info.declared_points[0] < info.declared_points[1]);
  CHECK(info.complete_levels == 3);
  CHECK(info.bytes_consumed == size);
  CHECK_STATUS(hmc_decoder_level_info(d, n - 1, &li), HMC_OK);
  CHECK(li.lod == 0);
  CHECK(li.point_count == 48 * 20);
  CHECK(li.stream_bytes <= size);
  CHECK_STATUS(hmc_decoder_level_info(d, 0, &li), HMC_OK);
  CHECK(li.lod == 2);
  CHECK(li.triangle_count > 0);
  CHECK_STATUS(hmc_decoder_level_points(d, n - 1, &pts, &count), HMC_OK);
  CHECK(count == 48 * 20);
  for (i = 0; i + 1 < count; ++i) /* canonical order: ascending (x, y, z) */
    CHECK(less3(pts + 3 * i, pts + 3 * i + 3));
  CHECK_STATUS(hmc_decoder_level_positions(d, n - 1, &xyz, &count), HMC_OK);
  CHECK(count == 48 * 20);
  for (i = 0; i < count; ++i) { /* on the torus, to within the grid step */
    const double r = sqrt(xyz[3 * i] * xyz[3 * i] + xyz[3 * i + 1] * xyz[3 * i + 1]) - 1.0;
    CHECK(fabs(sqrt(r * r + xyz[3 * i + 2] * xyz[3 * i + 2]) - 0.35) < 0.003);
  }
  CHECK_STATUS(hmc_decoder_level_triangles(d, n - 1, &tris, &count), HMC_OK);
  CHECK(count == 2 * 48 * 20); /* a closed genus-1 surface: 2V triangles */
  for (i = 0; i < 3 * count; ++i) CHECK(tris[i] < 48 * 20);
  CHECK_STATUS(hmc_decoder_level_tetrahedra(d, n - 1, &tets, &count), HMC_OK);
  CHECK(tets == NULL && count == 0);
  hmc_free(NULL, pts);
  hmc_free(NULL, xyz);
  hmc_free(NULL, tris);
  hmc_decoder_destroy(d);
  hmc_free(NULL, bytes);
}

static void test_volume(void) {
  double *ball = make_ball(300);
  hmc_encoder *e = hmc_encoder_create(NULL);
  hmc_decoder *d = hmc_decoder_create(NULL);
  hmc_encode_options o;
  uint8_t *bytes = NULL;
  size_t size = 0;
  hmc_level_info li;
  hmc_encode_options_init(&o);
  o.kind = HMC_KIND_VOLUME;
  o.levels = 2;
  o.bits = 14;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, ball, 300, NULL, 0, NULL, 0, &bytes, &size), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK(hmc_decoder_level_count(d) == 2);
  CHECK_STATUS(hmc_decoder_level_info(d, 1, &li), HMC_OK);
  CHECK(li.point_count == 300);
  CHECK(li.tetrahedron_count > 300);
  CHECK(li.triangle_count == 0);
  hmc_free(NULL, bytes);
  hmc_decoder_destroy(d);
  hmc_encoder_destroy(e);
  free(ball);
}

/* Same levels whether decoded at once or fed `piece` bytes at a time. */
static void test_streaming(size_t piece) {
  size_t size = 0, pos = 0, seen = 0, lvl;
  uint8_t *bytes = encode_torus(40, 16, 4, &size);
  hmc_decoder *whole = hmc_decoder_create(NULL), *d = hmc_decoder_create(NULL);
  hmc_stream_info info;
  CHECK_STATUS(hmc_decoder_decode(whole, bytes, size), HMC_OK);
  CHECK(hmc_decoder_level_count(whole) == 4);
  CHECK_STATUS(hmc_decoder_stream_info(d, &info), HMC_OK);
  CHECK(!info.header_ready);
  while (pos < size) {
    const size_t n = size - pos < piece ? size - pos : piece;
    CHECK_STATUS(hmc_decoder_feed(d, bytes + pos, n), HMC_OK);
    pos += n;
    while (seen < hmc_decoder_level_count(d)) { /* a new level: complete the moment its last byte is in */
      hmc_level_info a, b;
      CHECK_STATUS(hmc_decoder_level_info(d, seen, &a), HMC_OK);
      CHECK_STATUS(hmc_decoder_level_info(whole, seen, &b), HMC_OK);
      CHECK(a.stream_bytes <= pos && a.stream_bytes + piece > pos);
      CHECK(a.lod == b.lod && a.point_count == b.point_count && a.triangle_count == b.triangle_count);
      ++seen;
    }
  }
  CHECK_STATUS(hmc_decoder_stream_info(d, &info), HMC_OK);
  CHECK(info.header_ready && info.ended && info.declared_levels == 4);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_OK);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_OK);
  CHECK(seen == 4);
  for (lvl = 0; lvl < 4; ++lvl) {
    uint32_t *p1, *p2, *t1, *t2;
    size_t c1, c2, u1, u2;
    CHECK_STATUS(hmc_decoder_level_points(d, lvl, &p1, &c1), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_points(whole, lvl, &p2, &c2), HMC_OK);
    CHECK(c1 == c2 && memcmp(p1, p2, 3 * c1 * sizeof *p1) == 0);
    CHECK_STATUS(hmc_decoder_level_triangles(d, lvl, &t1, &u1), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_triangles(whole, lvl, &t2, &u2), HMC_OK);
    CHECK(u1 == u2 && memcmp(t1, t2, 3 * u1 * sizeof *t1) == 0);
    hmc_free(NULL, p1);
    hmc_free(NULL, p2);
    hmc_free(NULL, t1);
    hmc_free(NULL, t2);
  }
  /* Feeding after the end is misuse: refused, the decoder unchanged. */
  CHECK_STATUS(hmc_decoder_feed(d, bytes, 1), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_status(d), HMC_OK);
  hmc_decoder_destroy(d);
  hmc_decoder_destroy(whole);
  hmc_free(NULL, bytes);
}

/* Only the finest decoded level rebuilt: the same triangles as a full
   decode; coarser levels have none; a cut stream's last level is rebuilt
   at hmc_decoder_finish(). */
static void test_rebuild_finest(void) {
  size_t size = 0, lvl;
  uint8_t *bytes = encode_torus(40, 16, 4, &size);
  hmc_decoder *whole = hmc_decoder_create(NULL), *d = hmc_decoder_create(NULL), *cut = hmc_decoder_create(NULL);
  hmc_level_info a, b;
  uint32_t *t1, *t2;
  size_t u1, u2;
  CHECK_STATUS(hmc_decoder_set_rebuild_coarser_levels(NULL, 0), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_decode(whole, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_set_rebuild_coarser_levels(d, 0), HMC_OK);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_set_rebuild_coarser_levels(d, 1), HMC_INVALID_ARGUMENT);
  CHECK(hmc_decoder_level_count(d) == 4);
  for (lvl = 0; lvl < 4; ++lvl) {
    CHECK_STATUS(hmc_decoder_level_info(d, lvl, &a), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_info(whole, lvl, &b), HMC_OK);
    CHECK(a.point_count == b.point_count && b.triangle_count > 0);
    CHECK(a.triangle_count == (lvl == 3 ? b.triangle_count : 0));
  }
  CHECK_STATUS(hmc_decoder_level_triangles(d, 3, &t1, &u1), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_triangles(whole, 3, &t2, &u2), HMC_OK);
  CHECK(u1 == u2 && memcmp(t1, t2, 3 * u1 * sizeof *t1) == 0);
  hmc_free(NULL, t1);
  hmc_free(NULL, t2);
  /* Cut after level 2 (the second level sent): that level is rebuilt when the data ends. */
  CHECK_STATUS(hmc_decoder_level_info(whole, 1, &b), HMC_OK);
  CHECK_STATUS(hmc_decoder_set_rebuild_coarser_levels(cut, 0), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(cut, bytes, (size_t)b.stream_bytes), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_info(cut, 1, &a), HMC_OK);
  CHECK(a.triangle_count == 0);
  CHECK_STATUS(hmc_decoder_finish(cut), HMC_INCOMPLETE);
  CHECK(hmc_decoder_level_count(cut) == 2);
  CHECK_STATUS(hmc_decoder_level_info(cut, 1, &a), HMC_OK);
  CHECK(a.triangle_count == b.triangle_count && a.triangle_count > 0);
  CHECK_STATUS(hmc_decoder_level_info(cut, 0, &a), HMC_OK);
  CHECK(a.triangle_count == 0);
  hmc_decoder_destroy(cut);
  hmc_decoder_destroy(d);
  hmc_decoder_destroy(whole);
  hmc_free(NULL, bytes);
}

static void test_truncation(void) {
  size_t size = 0;
  uint8_t *bytes = encode_torus(40, 16, 3, &size);
  hmc_decoder *d = hmc_decoder_create(NULL);
  hmc_level_info first;
  hmc_stream_info info;
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_info(d, 0, &first), HMC_OK);
  hmc_decoder_destroy(d);

  /* Cut after the first level: incomplete, one level, truncated. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, (size_t)first.stream_bytes + 5), HMC_OK);
  CHECK(hmc_decoder_level_count(d) == 1);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_INCOMPLETE);
  CHECK(strstr(hmc_decoder_message(d), "decoded 1 of 3 levels") != NULL);
  CHECK_STATUS(hmc_decoder_status(d), HMC_INCOMPLETE);
  CHECK_STATUS(hmc_decoder_stream_info(d, &info), HMC_OK);
  CHECK(info.truncated && !info.ended);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_INCOMPLETE);
  hmc_decoder_destroy(d);

  /* The same cut decoded whole. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, (size_t)first.stream_bytes + 5), HMC_INCOMPLETE);
  CHECK(hmc_decoder_level_count(d) == 1);
  hmc_decoder_destroy(d);

  /* Cut before the first level: truncated, an error. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, 40), HMC_OK);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_TRUNCATED);
  CHECK(strlen(hmc_decoder_message(d)) > 0);
  CHECK(hmc_decoder_level_count(d) == 0);
  hmc_decoder_destroy(d);

  /* Nothing fed at all. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_TRUNCATED);
  CHECK(strstr(hmc_decoder_message(d), "empty") != NULL);
  hmc_decoder_destroy(d);
  hmc_free(NULL, bytes);
}

static void test_errors(void) {
  size_t size = 0;
  uint8_t *bytes = encode_torus(40, 16, 3, &size);
  uint8_t *bad = malloc(size);
  hmc_decoder *d;
  hmc_level_info li;
  size_t at;
  char message[512];

  /* A damaged byte in the finest level's layer chunk: CRC mismatch, whole
   * or streamed. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_level_info(d, 1, &li), HMC_OK);
  hmc_decoder_destroy(d);
  at = (size_t)li.stream_bytes + 20;
  memcpy(bad, bytes, size);
  bad[at] = (uint8_t)(bad[at] ^ 0x10);
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_decode(d, bad, size), HMC_CRC_MISMATCH);
  CHECK(strstr(hmc_decoder_message(d), "CRC") != NULL);
  CHECK(hmc_decoder_level_count(d) == 0);
  hmc_decoder_destroy(d);

  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_feed(d, bad, at), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bad + at, size - at), HMC_CRC_MISMATCH);
  strncpy(message, hmc_decoder_message(d), sizeof message - 1);
  message[sizeof message - 1] = 0;
  CHECK(strlen(message) > 0);
  /* Permanent failed state: everything returns the same error again. */
  CHECK_STATUS(hmc_decoder_status(d), HMC_CRC_MISMATCH);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, 10), HMC_CRC_MISMATCH);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_CRC_MISMATCH);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_CRC_MISMATCH);
  CHECK(strcmp(hmc_decoder_message(d), message) == 0);
  CHECK_STATUS(hmc_decoder_set_limits(d, 1, 1, 1), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_status(d), HMC_CRC_MISMATCH);
  /* Levels completed before the error stay readable. */
  CHECK(hmc_decoder_level_count(d) >= 1);
  hmc_decoder_destroy(d);

  /* Not an HMC stream: known from the first byte. */
  memcpy(bad, bytes, size);
  bad[0] = 'P';
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_feed(d, bad, 1), HMC_BAD_MAGIC);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, size), HMC_BAD_MAGIC);
  hmc_decoder_destroy(d);

  /* An unknown major version. */
  memcpy(bad, bytes, size);
  bad[8] = 7;
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_decode(d, bad, size), HMC_UNSUPPORTED_VERSION);
  hmc_decoder_destroy(d);

  /* Garbage after the end chunk. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, "x", 1), HMC_BAD_CHUNK);
  hmc_decoder_destroy(d);

  /* Errors as the whole-buffer decoder reports them: held until the end. */
  memcpy(bad, bytes, size);
  bad[at] = (uint8_t)(bad[at] ^ 0x10);
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_set_error_order(d, 7), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_error_order(d, HMC_ERRORS_AS_WHOLE), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bad, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, "xy", 2), HMC_OK);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_CRC_MISMATCH);
  CHECK_STATUS(hmc_decoder_set_error_order(d, HMC_ERRORS_IN_STREAM_ORDER), HMC_INVALID_ARGUMENT);
  hmc_decoder_destroy(d);

  free(bad);
  hmc_free(NULL, bytes);
}

static void test_limits_and_misuse(void) {
  size_t size = 0, count = 0;
  uint8_t *bytes = encode_torus(40, 16, 3, &size);
  hmc_decoder *d = hmc_decoder_create(NULL);
  uint64_t mp = 0, mb = 0;
  uint32_t ml = 0, *pts = (uint32_t *)1;
  hmc_level_info li;

  CHECK_STATUS(hmc_decoder_get_limits(d, &mp, &ml, &mb), HMC_OK);
  CHECK(mp == ((uint64_t)1 << 26) && ml == 64 && mb == ((uint64_t)1 << 32));
  CHECK_STATUS(hmc_decoder_set_limits(d, 100, 64, (uint64_t)1 << 20), HMC_OK);
  CHECK_STATUS(hmc_decoder_get_limits(d, &mp, &ml, &mb), HMC_OK);
  CHECK(mp == 100 && ml == 64 && mb == ((uint64_t)1 << 20));
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_LIMIT_EXCEEDED);
  CHECK(strstr(hmc_decoder_message(d), "limit") != NULL);
  hmc_decoder_destroy(d);

  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_set_limits(d, (uint64_t)1 << 26, 2, (uint64_t)1 << 32), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, size), HMC_LIMIT_EXCEEDED);
  hmc_decoder_destroy(d);

  /* Working memory: 2 GiB by default; 64 KiB cannot hold the torus' tetrahedra. */
  d = hmc_decoder_create(NULL);
  CHECK(hmc_decoder_memory_limit(d) == ((uint64_t)1 << 31));
  CHECK(hmc_decoder_memory_limit(NULL) == 0);
  CHECK_STATUS(hmc_decoder_set_memory_limit(NULL, 1), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_memory_limit(d, (uint64_t)1 << 16), HMC_OK);
  CHECK(hmc_decoder_memory_limit(d) == ((uint64_t)1 << 16));
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_LIMIT_EXCEEDED);
  CHECK(strstr(hmc_decoder_message(d), "memory limit") != NULL);
  CHECK_STATUS(hmc_decoder_set_memory_limit(d, (uint64_t)1 << 31), HMC_INVALID_ARGUMENT);
  hmc_decoder_destroy(d);

  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_set_limits(d, (uint64_t)1 << 26, 64, size - 1), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, size - 1), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bytes + size - 1, 1), HMC_LIMIT_EXCEEDED);
  hmc_decoder_destroy(d);

  /* Settings only before decoding; the coarser level asked for; points only. */
  d = hmc_decoder_create(NULL);
  CHECK_STATUS(hmc_decoder_set_finest_level(d, -1), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_finest_level(d, 1), HMC_OK);
  CHECK_STATUS(hmc_decoder_set_reconstruct(d, 0), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, 0), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, NULL, 0), HMC_OK);
  CHECK_STATUS(hmc_decoder_feed(d, NULL, 3), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_set_finest_level(d, 0), HMC_INVALID_ARGUMENT);
  CHECK(strlen(hmc_decoder_message(d)) > 0);
  CHECK_STATUS(hmc_decoder_set_reconstruct(d, 1), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_decode(d, bytes, size), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_feed(d, bytes, size), HMC_OK);
  CHECK_STATUS(hmc_decoder_finish(d), HMC_OK);
  CHECK(hmc_decoder_level_count(d) == 2);
  CHECK_STATUS(hmc_decoder_level_info(d, 1, &li), HMC_OK);
  CHECK(li.lod == 1 && li.triangle_count == 0);
  CHECK_STATUS(hmc_decoder_level_info(d, 2, &li), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_level_points(d, 2, &pts, &count), HMC_INVALID_ARGUMENT);
  CHECK(pts == NULL && count == 0);
  CHECK_STATUS(hmc_decoder_level_points(d, 0, NULL, &count), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_level_info(NULL, 0, &li), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_stream_info(d, NULL), HMC_INVALID_ARGUMENT);
  CHECK_STATUS(hmc_decoder_feed(NULL, bytes, 1), HMC_INVALID_ARGUMENT);
  CHECK(hmc_decoder_level_count(NULL) == 0);
  hmc_decoder_destroy(d);
  hmc_free(NULL, bytes);
}

/* ------------------------------------------------------- allocator hook */

typedef struct counter {
  long mallocs, reallocs, frees, live;
  long budget; /* allocations left before failing; negative: unlimited */
} counter;

static void *count_malloc(void *user, size_t n) {
  counter *c = user;
  void *p;
  if (c->budget == 0) return NULL;
  if (c->budget > 0) --c->budget;
  p = malloc(n);
  if (p) ++c->mallocs, ++c->live;
  return p;
}

static void *count_realloc(void *user, void *ptr, size_t n) {
  counter *c = user;
  ++c->reallocs;
  return realloc(ptr, n);
}

static void count_free(void *user, void *ptr) {
  counter *c = user;
  if (!ptr) return;
  ++c->frees, --c->live;
  free(ptr);
}

static void test_allocator(void) {
  counter c = {0, 0, 0, 0, -1};
  hmc_allocator a;
  hmc_allocator incomplete;
  hmc_encoder *e;
  hmc_decoder *d;
  mesh m = make_torus(40, 16);
  hmc_encode_options o;
  uint8_t *bytes = NULL;
  size_t size = 0, pos = 0, count = 0, lvl;
  a.malloc_fn = count_malloc;
  a.realloc_fn = count_realloc;
  a.free_fn = count_free;
  a.user = &c;

  e = hmc_encoder_create(&a);
  CHECK(e != NULL);
  CHECK(c.mallocs == 1);
  hmc_encode_options_init(&o);
  o.levels = 3;
  CHECK_STATUS(hmc_encoder_set_options(e, &o), HMC_OK);
  CHECK_STATUS(hmc_encoder_encode(e, m.xyz, m.points, m.tris, m.triangles, NULL, 0, &bytes, &size), HMC_OK);
  CHECK(c.mallocs == 2); /* the handle and the stream */
  hmc_encoder_destroy(e);
  CHECK(c.live == 1); /* the stream outlives its encoder */

  d = hmc_decoder_create(&a);
  CHECK(d != NULL);
  while (pos < size) { /* small pieces: the decoder buffers chunks in memory from the hook */
    const size_t n = size - pos < 50 ? size - pos : 50;
    CHECK_STATUS(hmc_decoder_feed(d, bytes + pos, n), HMC_OK);
    pos += n;
  }
  CHECK_STATUS(hmc_decoder_finish(d), HMC_OK);
  CHECK(c.reallocs > 0);
  for (lvl = 0; lvl < hmc_decoder_level_count(d); ++lvl) {
    uint32_t *p = NULL, *t = NULL;
    double *x = NULL;
    const long before = c.mallocs;
    CHECK_STATUS(hmc_decoder_level_points(d, lvl, &p, &count), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_positions(d, lvl, &x, &count), HMC_OK);
    CHECK_STATUS(hmc_decoder_level_triangles(d, lvl, &t, &count), HMC_OK);
    CHECK(c.mallocs == before + 3);
    hmc_free(&a, p);
    hmc_free(&a, x);
    hmc_free(&a, t);
  }
  /* An allocator that runs dry: out of memory, and the decoder goes on. */
  c.budget = 0;
  {
    uint32_t *p = (uint32_t *)1;
    CHECK_STATUS(hmc_decoder_level_points(d, 0, &p, &count), HMC_OUT_OF_MEMORY);
    CHECK(p == NULL && count == 0);
    CHECK(hmc_encoder_create(&a) == NULL);
    CHECK(hmc_decoder_create(&a) == NULL);
  }
  c.budget = -1;
  CHECK_STATUS(hmc_decoder_status(d), HMC_OK);
  hmc_decoder_destroy(d);
  hmc_free(&a, bytes);
  CHECK(c.mallocs > 3);
  CHECK(c.mallocs == c.frees);
  CHECK(c.live == 0);

  /* Every function is required. */
  incomplete = a;
  incomplete.realloc_fn = NULL;
  CHECK(hmc_decoder_create(&incomplete) == NULL);
  CHECK(hmc_encoder_create(&incomplete) == NULL);
  free(m.xyz);
  free(m.tris);
}

int main(void) {
  size_t pieces[] = {1, 7, 100, 100000};
  size_t i;
  test_strings();
  test_handles();
  test_encode_options();
  test_encoder_notes();
  test_threads();
  test_round_trip();
  test_preview();
  test_fast_decode();
  test_volume();
  for (i = 0; i < sizeof pieces / sizeof pieces[0]; ++i) test_streaming(pieces[i]);
  test_truncation();
  test_rebuild_finest();
  test_errors();
  test_limits_and_misuse();
  test_allocator();
  printf("test_capi: %d checks\n%d passed, %d failed\n", g_checks, g_checks - g_failures, g_failures);
  return g_failures ? 1 : 0;
}
