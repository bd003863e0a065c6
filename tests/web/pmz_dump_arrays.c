// SPDX-License-Identifier: MIT
/* pmz-dump-arrays: the native decoder's arrays, as the C API gives them, for the web tests
   (web/test/api.test.mjs compares the WebAssembly decoder's views with them bit for bit).

     pmz-dump-arrays FILE.pmz [FACES]   decodes FILE whole (FACES: that face target) and writes
                                        to stdout one JSON line (counts, materials, and each
                                        array's name and byte length), then the arrays' bytes in
                                        that order (little-endian, as in memory). */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "pmz/pmz.h"

static void json_string(const char* s) {
  putchar('"');
  for (; *s; ++s) {
    const unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\')
      printf("\\%c", c);
    else if (c < 0x20)
      printf("\\u%04x", c);
    else
      putchar(c);
  }
  putchar('"');
}

struct array {
  const char* name;
  const void* data;
  size_t bytes;
};

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    fprintf(stderr, "usage: pmz-dump-arrays FILE.pmz [FACES]\n");
    return 2;
  }
  FILE* f = fopen(argv[1], "rb");
  if (!f) {
    fprintf(stderr, "pmz-dump-arrays: %s: cannot open\n", argv[1]);
    return 1;
  }
  pmz_decoder* d = pmz_decoder_create(0, 0);
  static unsigned char buf[1 << 16];
  size_t n;
  int status = PMZ_OK;
  while (status == PMZ_OK && (n = fread(buf, 1, sizeof buf, f)) > 0)
    status = pmz_decoder_feed(d, buf, n);
  fclose(f);
  if (status == PMZ_OK) status = pmz_decoder_finish(d);
  if (argc == 3)
    pmz_decoder_set_face_target(d, strtoull(argv[2], NULL, 10));
  else
    pmz_decoder_refine(d, UINT64_MAX);
  if (status != PMZ_OK || pmz_decoder_status(d) != PMZ_OK) {
    fprintf(stderr, "pmz-dump-arrays: %s: %s\n", argv[1], pmz_decoder_error(d));
    pmz_decoder_destroy(d);
    return 1;
  }
  const size_t nv = pmz_decoder_vertex_count(d), nf = pmz_decoder_face_count(d);
  const size_t nw = pmz_decoder_wedge_count(d);
  const uint32_t sets = pmz_decoder_texcoord_set_count(d), cc = pmz_decoder_color_components(d);
  struct array arrays[16];
  int count = 0;
  arrays[count++] = (struct array){"positions", pmz_decoder_positions(d), nv * 12};
  arrays[count++] = (struct array){"indices", pmz_decoder_indices(d), nf * 12};
  if (nw) {
    arrays[count++] = (struct array){"wedgeVertices", pmz_decoder_wedge_vertices(d), nw * 4};
    arrays[count++] = (struct array){"wedgePositions", pmz_decoder_wedge_positions(d), nw * 12};
    arrays[count++] = (struct array){"wedgeIndices", pmz_decoder_wedge_indices(d), nf * 12};
    static const char* names[] = {"texcoords0", "texcoords1", "texcoords2", "texcoords3"};
    for (uint32_t s = 0; s < sets && s < 4; ++s)
      arrays[count++] = (struct array){names[s], pmz_decoder_texcoords(d, s), nw * 8};
    if (pmz_decoder_normals(d))
      arrays[count++] = (struct array){"normals", pmz_decoder_normals(d), nw * 12};
    if (pmz_decoder_colors(d))
      arrays[count++] = (struct array){"colors", pmz_decoder_colors(d), nw * cc * 4};
  }
  if (pmz_decoder_face_materials(d))
    arrays[count++] = (struct array){"faceMaterials", pmz_decoder_face_materials(d), nf * 4};

  printf(
      "{\"vertices\":%zu,\"faces\":%zu,\"wedges\":%zu,\"texcoordSets\":%u,"
      "\"colorComponents\":%u,\"materials\":[",
      nv, nf, nw, sets, cc);
  pmz_material m;
  for (uint32_t i = 0; pmz_decoder_material(d, i, &m); ++i) {
    printf("%s{\"name\":", i ? "," : "");
    json_string(m.name);
    printf(",\"baseColorTexture\":");
    json_string(m.base_color_texture);
    printf(",\"normalTexture\":");
    json_string(m.normal_texture);
    printf(",\"baseColor\":[%.9g,%.9g,%.9g,%.9g]}", m.base_color[0], m.base_color[1],
           m.base_color[2], m.base_color[3]);
  }
  printf("],\"arrays\":[");
  for (int i = 0; i < count; ++i)
    printf("%s[\"%s\",%zu]", i ? "," : "", arrays[i].name, arrays[i].bytes);
  printf("]}\n");
  for (int i = 0; i < count; ++i)
    if (arrays[i].bytes) fwrite(arrays[i].data, 1, arrays[i].bytes, stdout);
  pmz_decoder_destroy(d);
  return fflush(stdout) == 0 ? 0 : 1;
}
