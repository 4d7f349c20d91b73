/* SPDX-License-Identifier: AGPL-3.0-or-later */
/*
 * stream_levels: decode an HMC stream from standard input while it arrives,
 * and print each level of detail the moment it is complete.
 *
 *   hmc gen torus --vertices 20000 -o torus.ply
 *   hmc enc torus.ply -o torus.hmc --levels 4
 *   stream_levels --rate 20000 < torus.hmc
 *
 * --rate BYTES_PER_SECOND throttles the input as a slow network would (the
 * bytes are handed to the decoder no faster than that); --piece BYTES sets
 * how much is read and fed at a time (default: a twentieth of a second's
 * worth, or 64 KiB unthrottled). Exit status: 0 for a complete stream or one
 * cut after a complete level, 3 for an invalid stream, 1 for a bad command
 * line.
 *
 * The C API is poll style: after each hmc_decoder_feed(), levels
 * 0 .. hmc_decoder_level_count() - 1 are complete (coarsest first).
 */
#define _POSIX_C_SOURCE 199309L

#include <hmc/hmc.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static void sleep_until(double t) {
  double left = t - now();
  while (left > 0) {
    struct timespec ts;
    ts.tv_sec = (time_t)left;
    ts.tv_nsec = (long)((left - (double)ts.tv_sec) * 1e9);
    nanosleep(&ts, NULL);
    left = t - now();
  }
}

static int usage(const char *why) {
  fprintf(stderr,
          "stream_levels: %s\n"
          "usage: stream_levels [--rate BYTES_PER_SECOND] [--piece BYTES] < STREAM.hmc\n",
          why);
  return 1;
}

static const char *kind_name(int kind) {
  return kind == HMC_KIND_SURFACE ? "surface" : kind == HMC_KIND_VOLUME ? "volume" : "points";
}

static int parse_size(const char *s, unsigned long long *out) {
  char *end = NULL;
  *out = strtoull(s, &end, 10);
  return end != s && *end == 0 && *out > 0;
}

int main(int argc, char **argv) {
  unsigned long long rate = 0, piece = 0, total = 0;
  int i, header_printed = 0, exit_code = 0;
  size_t seen = 0;
  unsigned char *buf;
  hmc_decoder *dec;
  hmc_status st = HMC_OK;
  double t0;

  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--rate") == 0 && i + 1 < argc) {
      if (!parse_size(argv[++i], &rate)) return usage("--rate needs a positive number of bytes per second");
    } else if (strcmp(argv[i], "--piece") == 0 && i + 1 < argc) {
      if (!parse_size(argv[++i], &piece)) return usage("--piece needs a positive number of bytes");
    } else {
      return usage(strcmp(argv[i], "--help") == 0 ? "decode a stream from standard input as it arrives"
                                                   : "unknown argument");
    }
  }
  if (!piece) piece = rate ? (rate / 20 ? rate / 20 : 1) : 65536;

  dec = hmc_decoder_create(NULL);
  buf = malloc((size_t)piece);
  if (!dec || !buf) {
    fprintf(stderr, "stream_levels: out of memory\n");
    return 6;
  }
  printf("libhmc %s, reading standard input%s\n", hmc_version_string(), rate ? " (throttled)" : "");
  t0 = now();
  for (;;) {
    const size_t n = fread(buf, 1, (size_t)piece, stdin);
    if (n == 0) break;
    if (rate) sleep_until(t0 + (double)(total + n) / (double)rate); /* the bytes "arrive" at the rate */
    total += n;
    st = hmc_decoder_feed(dec, buf, n);
    if (!header_printed) {
      hmc_stream_info info;
      hmc_decoder_stream_info(dec, &info);
      if (info.header_ready) {
        uint32_t k;
        printf("[%6.2f s] header: %s, q = %d, %u levels declared, points per level:", now() - t0,
               kind_name(info.kind), info.bits, (unsigned)info.declared_levels);
        for (k = 0; k < info.declared_levels; ++k) printf(" %llu", (unsigned long long)info.declared_points[k]);
        printf("\n");
        header_printed = 1;
      }
    }
    for (; seen < hmc_decoder_level_count(dec); ++seen) {
      hmc_level_info li;
      hmc_decoder_level_info(dec, seen, &li);
      printf("[%6.2f s] level %d complete after %llu bytes: %llu vertices, ", now() - t0, li.lod,
             (unsigned long long)li.stream_bytes, (unsigned long long)li.point_count);
      if (li.tetrahedron_count)
        printf("%llu tetrahedra\n", (unsigned long long)li.tetrahedron_count);
      else
        printf("%llu triangles\n", (unsigned long long)li.triangle_count);
      fflush(stdout);
    }
    if (st != HMC_OK) break;
  }
  if (ferror(stdin)) {
    fprintf(stderr, "stream_levels: cannot read standard input\n");
    exit_code = 2;
  } else {
    if (st == HMC_OK) st = hmc_decoder_finish(dec);
    if (st == HMC_OK) {
      printf("[%6.2f s] end of stream: %llu bytes, %lu levels\n", now() - t0, total, (unsigned long)seen);
    } else if (st == HMC_INCOMPLETE) {
      printf("[%6.2f s] the stream was cut: %s\n", now() - t0, hmc_decoder_message(dec));
    } else {
      fprintf(stderr, "stream_levels: %s: %s\n", hmc_status_string(st), hmc_decoder_message(dec));
      exit_code = 3;
    }
  }
  free(buf);
  hmc_decoder_destroy(dec);
  return exit_code;
}
