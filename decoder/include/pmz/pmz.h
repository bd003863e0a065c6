// SPDX-License-Identifier: MIT
/* pmz streaming decoder: C API (a thin layer over pmz::Decoder, pmz/decoder.hpp).

   A .pmz stream holds a coarse base mesh and then vertex splits that refine it to the full
   mesh. The decoder takes the stream's bytes as they arrive, in slices of any size (push model,
   as zstd's ZSTD_decompressStream): feeding one byte at a time or the whole file gives the same
   result. Decoded splits become *available*; the level-of-detail calls move the current mesh
   between the base mesh and the finest level available without re-reading bytes.

   Conventions for every function below:
   - Decoder handles: a pmz_decoder* argument must come from pmz_decoder_create() and not yet
     be destroyed (NULL is accepted by pmz_decoder_destroy() only). Output struct pointers
     (pmz_stream_info*, pmz_changes*, pmz_material*) must be non-NULL.
   - Errors: functions return a status (PMZ_OK or a PMZ_ERR_* code) or a count; nothing aborts
     or prints, and no C++ exception crosses the API. pmz_decoder_status() and
     pmz_decoder_error() report an error until the decoder is destroyed: after one, feeding
     stops (pmz_decoder_feed() and _finish() return it again), and the mesh stays a valid mesh
     at the level it had (still usable; the splits decoded before the error can still be
     applied). Each split's wedge and position are decoded when it is first applied, so the
     level-of-detail calls can also find damage (PMZ_ERR_CORRUPT), reach the face limit
     (PMZ_ERR_LIMIT) or run out of memory (PMZ_ERR_MEMORY): check pmz_decoder_status() after
     them.
   - Pointers returned by the decoder (mesh arrays, the change list, strings) point into the
     decoder: never free them. Array pointers stay valid until the next call that changes the
     mesh on that decoder (pmz_decoder_feed, _refine, _coarsen, _set_face_target,
     _set_split_target) or its destruction; strings as each function says. Pointers passed in
     are not kept: the decoder copies what it needs before returning.
   - Threads: there is no global state. Different decoders may be used from different threads
     at the same time; one decoder must not be used from two threads at once (the const
     accessors may run together, but not alongside any other call on it). pmz_version() and
     pmz_status_name() may be called from any thread at any time. */
#ifndef PMZ_H
#define PMZ_H
#include <stddef.h>
#include <stdint.h>

#include "pmz/export.h"

/* ---- Version ---- */

/* The library's version (the CMake project's version is read from these lines). */
#define PMZ_VERSION_MAJOR 0
#define PMZ_VERSION_MINOR 1
#define PMZ_VERSION_PATCH 0
#define PMZ_VERSION_NUMBER (PMZ_VERSION_MAJOR * 10000 + PMZ_VERSION_MINOR * 100 + PMZ_VERSION_PATCH)

#ifdef __cplusplus
extern "C" {
#endif

/* PMZ_VERSION_NUMBER of the library linked at run time (which may differ from the header's
   with a shared library). Thread-safe; never fails. */
PMZ_API uint32_t pmz_version(void);

/* ---- Status codes ---- */

enum {
  PMZ_OK = 0,
  PMZ_ERR_MAGIC = 1,     /* not a .pmz stream */
  PMZ_ERR_VERSION = 2,   /* a major format version this decoder does not read */
  PMZ_ERR_CHECKSUM = 3,  /* a chunk's checksum does not match its bytes */
  PMZ_ERR_CORRUPT = 4,   /* bytes that parse but describe an impossible mesh or stream */
  PMZ_ERR_LIMIT = 5,     /* counts beyond the decoder's limits or beyond what the input holds */
  PMZ_ERR_TRUNCATED = 6, /* only from pmz_decoder_finish(): the stream ended early */
  PMZ_ERR_MEMORY = 7     /* an allocation failed */
};

/* "ok", "bad magic", ...: the names the one-line errors use; "unknown" for any other value.
   A static string (never NULL, never freed). Thread-safe. */
PMZ_API const char* pmz_status_name(int status);

/* ---- Decoder lifetime ---- */

typedef struct pmz_decoder pmz_decoder;

/* A new decoder, waiting for the stream's first byte. max_vertices and max_faces cap the mesh
   (checked against the header's counts before any allocation; beyond them: PMZ_ERR_LIMIT);
   0 takes the default (2^27 vertices, 2^28 faces). Returns NULL only when out of memory.
   Release it with pmz_decoder_destroy(). */
PMZ_API pmz_decoder* pmz_decoder_create(uint64_t max_vertices, uint64_t max_faces);
/* Releases d and everything it returned (arrays, strings, materials). NULL is a no-op. */
PMZ_API void pmz_decoder_destroy(pmz_decoder* d);

/* ---- Input ---- */

/* Consumes the next `size` bytes of the stream (data may be NULL when size is 0). Bytes are
   copied as needed: data need not outlive the call. Returns PMZ_OK or the stream's first
   error; after an error, further feeds read nothing and return it again. Bytes after the
   stream's end marker are ignored. May install the base mesh (the mesh changes). */
PMZ_API int pmz_decoder_feed(pmz_decoder* d, const void* data, size_t size);
/* Call at the end of the input: PMZ_ERR_TRUNCATED (and sticky) if the end marker was not seen,
   else the current status. The mesh and the splits decoded so far stay usable. */
PMZ_API int pmz_decoder_finish(pmz_decoder* d);
/* The current status: PMZ_OK or the error (see the conventions above). */
PMZ_API int pmz_decoder_status(const pmz_decoder* d);
/* One line describing the error ("pmz: corrupt stream: ... (chunk 3 at byte 1234)"), "" when
   the status is PMZ_OK. Owned by d: valid until the next call on d other than the const
   accessors, or its destruction. Never NULL. */
PMZ_API const char* pmz_decoder_error(const pmz_decoder* d);
/* The bytes fed while the status was PMZ_OK, including those still waiting for the rest of
   their chunk. */
PMZ_API uint64_t pmz_decoder_bytes_consumed(const pmz_decoder* d);

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
/* Fills *out (all zero before the header is in). */
PMZ_API void pmz_decoder_info(const pmz_decoder* d, pmz_stream_info* out);

/* Decoding threads for the level-of-detail calls below: 0 (the default) uses the machine's
   cores (std::thread::hardware_concurrency), 1 the calling thread only. The mesh, ids, change
   report and errors are the same for every count (only streams with a node table and without
   attributes use more than one; the WebAssembly build always uses one). Never fails. */
PMZ_API void pmz_decoder_set_threads(pmz_decoder* d, uint32_t threads);

/* ---- Level of detail ---- */

/* Applies up to max_splits available splits (UINT64_MAX: all); returns how many were applied
   (fewer when no more are available, or when an error stops it: check the status). */
PMZ_API uint64_t pmz_decoder_refine(pmz_decoder* d, uint64_t max_splits);
/* Undoes up to max_splits applied splits, the last first; returns how many were undone. */
PMZ_API uint64_t pmz_decoder_coarsen(pmz_decoder* d, uint64_t max_splits);
/* Moves to the coarsest level holding at least `faces` faces, clamped to the base mesh and to
   the finest level available. */
PMZ_API void pmz_decoder_set_face_target(pmz_decoder* d, uint64_t faces);
/* Moves to the level with `splits` splits applied, clamped to those available. */
PMZ_API void pmz_decoder_set_split_target(pmz_decoder* d, uint64_t splits);
PMZ_API uint64_t pmz_decoder_splits_applied(const pmz_decoder* d);
/* Splits decoded so far: the finest level pmz_decoder_refine() can reach now. */
PMZ_API uint64_t pmz_decoder_splits_available(const pmz_decoder* d);
/* The stream's split count from its header; 0 until the header is in. */
PMZ_API uint64_t pmz_decoder_total_splits(const pmz_decoder* d);

/* ---- The current mesh ----
   A consistent indexed triangle mesh after every call: vertex_count vertices, face_count
   counter-clockwise faces. Before the base mesh is in, counts are 0 and the arrays NULL. */

PMZ_API uint32_t pmz_decoder_vertex_count(const pmz_decoder* d);
PMZ_API uint32_t pmz_decoder_face_count(const pmz_decoder* d);
PMZ_API const float* pmz_decoder_positions(const pmz_decoder* d);  /* 3 floats per vertex */
PMZ_API const uint32_t* pmz_decoder_indices(const pmz_decoder* d); /* 3 indices per face */
/* For geomorphs: the vertex each vertex was split from (UINT32_MAX for base vertices). */
PMZ_API const uint32_t* pmz_decoder_split_parents(const pmz_decoder* d);

/* ---- View-dependent decoding (streams with a node table) ----
   As pmz::Decoder's update_view, feed_node, node_range, view_complete, nodes_to_fetch and
   nodes_applied (pmz/decoder.hpp states the contract): feed the stream in order up to its node
   table, then the byte ranges of the nodes a view needs, in any order. */
typedef struct pmz_view {
  float eye[3];              /* the mesh's coordinates */
  float view_projection[16]; /* column-major clip-from-mesh matrix */
  float fov_y;               /* radians */
  uint32_t viewport_height;  /* pixels */
  float pixel_error;         /* refine while a node's error spans more pixels than this */
} pmz_view;
/* Fills *out for a camera at eye looking at target (y up), width x height pixels. */
PMZ_API void pmz_view_look_at(pmz_view* out, const float eye[3], const float target[3], float fov_y,
                              uint32_t width, uint32_t height, float near, float pixel_error);
PMZ_API uint64_t pmz_decoder_update_view(pmz_decoder* d, const pmz_view* view, uint64_t max_splits);
/* A face budget for the nodes update_view applies, from the next call on (0, the default: none):
   as pmz::Decoder's set_view_face_budget, which states what it admits. */
PMZ_API void pmz_decoder_set_view_face_budget(pmz_decoder* d, uint64_t faces);
PMZ_API int pmz_decoder_view_complete(const pmz_decoder* d); /* 1 or 0 */
/* The nodes to fetch next (*count of them); owned by d, valid until the next update_view. */
PMZ_API const uint32_t* pmz_decoder_nodes_to_fetch(const pmz_decoder* d, size_t* count);
/* Node k's byte range: 1, or 0 before the table arrived or for k out of range. */
PMZ_API int pmz_decoder_node_range(const pmz_decoder* d, uint32_t k, uint64_t* offset,
                                   uint64_t* size);
PMZ_API int pmz_decoder_feed_node(pmz_decoder* d, uint32_t k, const void* data, size_t size);
PMZ_API uint32_t pmz_decoder_nodes_applied(const pmz_decoder* d);

/* ---- Changes, for partial uploads ---- */

/* What changed in the mesh since the last pmz_decoder_clear_changes(): vertices
   [vertex_begin, vertex_count) and faces [face_begin, face_count) are new or rewritten;
   modified_faces lists faces below face_begin whose indices were rewritten (may repeat,
   unsorted; modified_count of them; owned by d, valid until the next call that changes the
   mesh or clears the changes); all asks for a full re-upload. */
typedef struct pmz_changes {
  uint32_t vertex_begin;
  uint32_t face_begin;
  const uint32_t* modified_faces;
  size_t modified_count;
  uint32_t all;
  uint32_t wedge_begin; /* attribute wedges [wedge_begin, wedge_count) are new; a face's wedge
                           indices change exactly when its vertex indices do */
} pmz_changes;
/* Fills *out with the changes so far. */
PMZ_API void pmz_decoder_changes(const pmz_decoder* d, pmz_changes* out);
/* Starts a new change report (after the caller has uploaded the last one). */
PMZ_API void pmz_decoder_clear_changes(pmz_decoder* d);

/* ---- Attributes and materials ----
   Format 8.0 (spec/format.md section 14), as pmz::Decoder's accessors: a render vertex is an
   attribute wedge (one combination of attribute values at one position vertex). Without
   attributes in the stream (or before its base mesh): wedge count 0 and NULL arrays. Arrays
   hold wedge_count wedges and face_count faces, with the lifetime of the mesh arrays. */

PMZ_API uint32_t pmz_decoder_wedge_count(const pmz_decoder* d);
PMZ_API const uint32_t* pmz_decoder_wedge_vertices(const pmz_decoder* d); /* -> vertex index */
PMZ_API const float* pmz_decoder_wedge_positions(const pmz_decoder* d);   /* 3 per wedge */
PMZ_API const uint32_t* pmz_decoder_wedge_indices(const pmz_decoder* d);  /* 3 per face */
PMZ_API uint32_t pmz_decoder_texcoord_set_count(const pmz_decoder* d);
/* u, v per wedge of texture coordinate set `set`; NULL for set >= the set count. */
PMZ_API const float* pmz_decoder_texcoords(const pmz_decoder* d, uint32_t set);
PMZ_API const float* pmz_decoder_normals(const pmz_decoder* d);      /* xyz, or NULL */
PMZ_API uint32_t pmz_decoder_color_components(const pmz_decoder* d); /* 0, 3 or 4 */
PMZ_API const float* pmz_decoder_colors(const pmz_decoder* d);       /* or NULL */
/* Per face an index into the material table; NULL without materials. */
PMZ_API const uint32_t* pmz_decoder_face_materials(const pmz_decoder* d);
PMZ_API uint32_t pmz_decoder_material_count(const pmz_decoder* d);
typedef struct pmz_material {
  const char* name;               /* strings owned by the decoder, never NULL */
  const char* base_color_texture; /* file name or URI, "" when none */
  const char* normal_texture;
  float base_color[4];
} pmz_material;
/* Fills *out and returns 1, or returns 0 when i >= material count. The strings stay valid
   until pmz_decoder_destroy(d) (the material table is read once, with the header). */
PMZ_API int pmz_decoder_material(const pmz_decoder* d, uint32_t i, pmz_material* out);

#ifdef __cplusplus
}
#endif
#endif
