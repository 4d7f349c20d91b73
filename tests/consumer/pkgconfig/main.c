/* SPDX-License-Identifier: AGPL-3.0-or-later */
/* Out-of-tree consumer (plain C99, pkg-config): streams a file through the
 * C API in small pieces, prints each level as it completes, and compares
 * the finest level with a whole-buffer decode. */
#include <hmc/hmc.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv) {
  FILE *f;
  unsigned char *bytes;
  long size;
  size_t pos, seen = 0, n1 = 0, n2 = 0;
  hmc_decoder *dec, *whole;
  hmc_status st;
  uint32_t *p1, *p2;
  int same;
  if (argc != 2) {
    fprintf(stderr, "usage: consumer_c STREAM.hmc\n");
    return 1;
  }
  f = fopen(argv[1], "rb");
  if (!f || fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) <= 0 || fseek(f, 0, SEEK_SET) != 0) return 2;
  bytes = malloc((size_t)size);
  if (!bytes || fread(bytes, 1, (size_t)size, f) != (size_t)size) return 2;
  fclose(f);

  dec = hmc_decoder_create(NULL);
  for (pos = 0; pos < (size_t)size; pos += 501) {
    const size_t n = (size_t)size - pos < 501 ? (size_t)size - pos : 501;
    st = hmc_decoder_feed(dec, bytes + pos, n);
    if (st != HMC_OK) {
      fprintf(stderr, "consumer_c: %s: %s\n", hmc_status_string(st), hmc_decoder_message(dec));
      return 3;
    }
    for (; seen < hmc_decoder_level_count(dec); ++seen) {
      hmc_level_info li;
      hmc_decoder_level_info(dec, seen, &li);
      printf("level %d: %llu vertices, %llu triangles\n", li.lod, (unsigned long long)li.point_count,
             (unsigned long long)li.triangle_count);
    }
  }
  st = hmc_decoder_finish(dec);
  if (st != HMC_OK) {
    fprintf(stderr, "consumer_c: finish: %s: %s\n", hmc_status_string(st), hmc_decoder_message(dec));
    return 3;
  }
  whole = hmc_decoder_create(NULL);
  if (hmc_decoder_decode(whole, bytes, (size_t)size) != HMC_OK || hmc_decoder_level_count(whole) != seen) return 4;
  if (hmc_decoder_level_points(dec, seen - 1, &p1, &n1) != HMC_OK ||
      hmc_decoder_level_points(whole, seen - 1, &p2, &n2) != HMC_OK)
    return 4;
  same = n1 == n2 && memcmp(p1, p2, 3 * n1 * sizeof *p1) == 0;
  printf("consumer_c: %lu levels, libhmc %s; streamed and whole decoding %s\n", (unsigned long)seen,
         hmc_version_string(), same ? "agree" : "DISAGREE");
  hmc_free(NULL, p1);
  hmc_free(NULL, p2);
  hmc_decoder_destroy(dec);
  hmc_decoder_destroy(whole);
  free(bytes);
  return same ? 0 : 5;
}
