// SPDX-License-Identifier: MIT
/* pmz streaming decoder: C API (a thin layer over pmz::Decoder). */
#ifndef PMZ_H
#define PMZ_H
#include <stddef.h>
#include <stdint.h>

#include "pmz/export.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pmz_decoder pmz_decoder;

enum {
  PMZ_OK = 0,
  PMZ_ERR_MAGIC = 1,
  PMZ_ERR_VERSION = 2,
  PMZ_ERR_CHECKSUM = 3,
  PMZ_ERR_CORRUPT = 4,
  PMZ_ERR_LIMIT = 5,
  PMZ_ERR_TRUNCATED = 6,
  PMZ_ERR_MEMORY = 7
};

/* Limits of 0 take the defaults. Returns NULL only when out of memory. */
PMZ_API pmz_decoder* pmz_decoder_create(uint64_t max_vertices, uint64_t max_faces);
PMZ_API void pmz_decoder_destroy(pmz_decoder* d);

PMZ_API int pmz_decoder_feed(pmz_decoder* d, const void* data, size_t size);
PMZ_API int pmz_decoder_finish(pmz_decoder* d);
PMZ_API const char* pmz_decoder_error(const pmz_decoder* d); /* one line; "" when ok */
/* The sticky status (PMZ_OK or the error). refine, coarsen and set_face_target can set it
   too: each split's wedge and position are decoded when it is first applied, so damage there
   (PMZ_ERR_CORRUPT) or an allocation failure (PMZ_ERR_MEMORY) shows only then; the mesh stays
   at the level reached. */
PMZ_API int pmz_decoder_status(const pmz_decoder* d);

PMZ_API uint64_t pmz_decoder_refine(pmz_decoder* d, uint64_t max_splits);
PMZ_API uint64_t pmz_decoder_coarsen(pmz_decoder* d, uint64_t max_splits);
PMZ_API void pmz_decoder_set_face_target(pmz_decoder* d, uint64_t faces);
PMZ_API uint64_t pmz_decoder_splits_applied(const pmz_decoder* d);
PMZ_API uint64_t pmz_decoder_splits_available(const pmz_decoder* d);
PMZ_API uint64_t pmz_decoder_total_splits(const pmz_decoder* d); /* 0 until the header is in */

PMZ_API uint32_t pmz_decoder_vertex_count(const pmz_decoder* d);
PMZ_API uint32_t pmz_decoder_face_count(const pmz_decoder* d);
PMZ_API const float* pmz_decoder_positions(const pmz_decoder* d);  /* 3 floats per vertex */
PMZ_API const uint32_t* pmz_decoder_indices(const pmz_decoder* d); /* 3 indices per face */
/* For geomorphs: the vertex each vertex was split from (UINT32_MAX for base vertices). */
PMZ_API const uint32_t* pmz_decoder_split_parents(const pmz_decoder* d);

/* "ok", "bad magic", ...: the names the one-line errors use; "unknown" for other values. */
PMZ_API const char* pmz_status_name(int status);
PMZ_API uint64_t pmz_decoder_bytes_consumed(const pmz_decoder* d);
PMZ_API void pmz_decoder_set_split_target(pmz_decoder* d, uint64_t splits);

/* The stream's header fields (valid once header_done) and progress. */
typedef struct pmz_stream_info {
  uint64_t base_vertices, base_faces;
  uint64_t full_vertices, full_faces;
  uint64_t total_splits;
  uint32_t header_done; /* header parsed: the fields are valid */
  uint32_t base_done;   /* base mesh decoded: the mesh is drawable */
  uint32_t complete;    /* end marker seen: every split is available */
  uint32_t version_major, version_minor;
  uint32_t flags;
  uint32_t position_bits; /* 0 = lossless float32 */
  uint32_t curvature, fine_curvature;
  float bbox_min[3], bbox_max[3];
  uint32_t level; /* compression level: 0 default, 1 speed */
} pmz_stream_info;
PMZ_API void pmz_decoder_info(const pmz_decoder* d, pmz_stream_info* out);

/* What changed in the mesh since the last pmz_decoder_clear_changes(), for partial uploads:
   vertices [vertex_begin, vertex_count) and faces [face_begin, face_count) are new or
   rewritten; modified_faces lists faces below face_begin whose indices were rewritten (may
   repeat, unsorted; valid until the next call that changes the mesh); all asks for a full
   re-upload. */
typedef struct pmz_changes {
  uint32_t vertex_begin;
  uint32_t face_begin;
  const uint32_t* modified_faces;
  size_t modified_count;
  uint32_t all;
  uint32_t wedge_begin; /* attribute wedges [wedge_begin, wedge_count) are new; a face's wedge
                           indices change exactly when its vertex indices do */
} pmz_changes;
PMZ_API void pmz_decoder_changes(const pmz_decoder* d, pmz_changes* out);
PMZ_API void pmz_decoder_clear_changes(pmz_decoder* d);

/* Attributes (format 8.0, spec/format.md section 14), as pmz::Decoder's accessors: a render
   vertex is an attribute wedge (one combination of attribute values at one position vertex).
   Without attributes: wedge count 0 and NULL arrays. Arrays hold wedge_count wedges and
   face_count faces and stay valid until the next call that changes the level. */
PMZ_API uint32_t pmz_decoder_wedge_count(const pmz_decoder* d);
PMZ_API const uint32_t* pmz_decoder_wedge_vertices(const pmz_decoder* d); /* -> vertex index */
PMZ_API const float* pmz_decoder_wedge_positions(const pmz_decoder* d);   /* 3 per wedge */
PMZ_API const uint32_t* pmz_decoder_wedge_indices(const pmz_decoder* d);  /* 3 per face */
PMZ_API uint32_t pmz_decoder_texcoord_set_count(const pmz_decoder* d);
PMZ_API const float* pmz_decoder_texcoords(const pmz_decoder* d, uint32_t set); /* u, v */
PMZ_API const float* pmz_decoder_normals(const pmz_decoder* d);                 /* xyz */
PMZ_API uint32_t pmz_decoder_color_components(const pmz_decoder* d);            /* 0, 3, 4 */
PMZ_API const float* pmz_decoder_colors(const pmz_decoder* d);
/* Per face an index into the material table; NULL without materials. */
PMZ_API const uint32_t* pmz_decoder_face_materials(const pmz_decoder* d);
PMZ_API uint32_t pmz_decoder_material_count(const pmz_decoder* d);
typedef struct pmz_material {
  const char* name;               /* strings owned by the decoder, never NULL */
  const char* base_color_texture; /* file name or URI, "" when none */
  const char* normal_texture;
  float base_color[4];
} pmz_material;
/* Fills *out and returns 1, or returns 0 when i >= material count. */
PMZ_API int pmz_decoder_material(const pmz_decoder* d, uint32_t i, pmz_material* out);

#ifdef __cplusplus
}
#endif
#endif
