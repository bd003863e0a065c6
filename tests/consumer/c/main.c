// SPDX-License-Identifier: MIT
/* A C program that links pmz::decoder through the installed CMake package and decodes a real
   .pmz file (argv[1]) through the C API: feed it in small slices, refine, check the mesh, the
   stream info and the change report. */
#include <pmz/pmz.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char** argv) {
  if (argc < 2) return 1;
  FILE* f = fopen(argv[1], "rb");
  if (!f) return 1;
  static unsigned char bytes[1 << 16];
  size_t n = fread(bytes, 1, sizeof bytes, f);
  fclose(f);
  pmz_decoder* d = pmz_decoder_create(0, 0);
  if (!d) return 1;
  for (size_t at = 0; at < n; at += 7) {
    size_t len = n - at < 7 ? n - at : 7;
    if (pmz_decoder_feed(d, bytes + at, len) != PMZ_OK) {
      printf("consumer: %s\n", pmz_decoder_error(d));
      return 1;
    }
  }
  int rc = pmz_decoder_finish(d);
  uint64_t applied = pmz_decoder_refine(d, UINT64_MAX);
  uint32_t nv = pmz_decoder_vertex_count(d), nf = pmz_decoder_face_count(d);
  const uint32_t* idx = pmz_decoder_indices(d);
  pmz_stream_info info;
  pmz_decoder_info(d, &info);
  pmz_changes changes;
  pmz_decoder_changes(d, &changes);
  int ok = rc == PMZ_OK && nf > 0 && applied == pmz_decoder_total_splits(d) && info.complete &&
           info.full_faces == nf && info.full_vertices == nv &&
           pmz_decoder_bytes_consumed(d) == n && (changes.all || changes.face_begin < nf);
  for (uint32_t i = 0; ok && i < nf * 3; ++i) ok = idx[i] < nv;
  const char junk[] = "not a pmz stream";
  pmz_decoder* bad = pmz_decoder_create(0, 0);
  /* The installed header and library are one version. */
  ok = ok && pmz_version() == PMZ_VERSION_NUMBER;
  ok = ok && pmz_decoder_feed(bad, junk, sizeof junk) == PMZ_ERR_MAGIC &&
       strlen(pmz_decoder_error(bad)) > 0 && strcmp(pmz_status_name(PMZ_ERR_MAGIC), "ok") != 0;
  printf("consumer: %u vertices, %u faces after %llu splits; junk -> %s\n", nv, nf,
         (unsigned long long)applied, pmz_decoder_error(bad));
  pmz_decoder_destroy(bad);
  pmz_decoder_destroy(d);
  return ok ? 0 : 1;
}
