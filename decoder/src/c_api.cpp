// SPDX-License-Identifier: MIT
// C API: a thin layer over pmz::Decoder; no exception crosses it.
#include <algorithm>
#include <new>

#include "pmz/decoder.hpp"
#include "pmz/export.h"
#include "pmz/pmz.h"
#include "pmz/wasm_hints.hpp"

struct pmz_decoder {
  pmz::Decoder dec;
  explicit pmz_decoder(const pmz::DecoderLimits& l) : dec(l) {}
};

extern "C" {

PMZ_API pmz_decoder* pmz_decoder_create(uint64_t max_vertices, uint64_t max_faces) {
  pmz::DecoderLimits limits;
  if (max_vertices) limits.max_vertices = max_vertices;
  if (max_faces) limits.max_faces = max_faces;
  return new (std::nothrow) pmz_decoder(limits);
}
PMZ_API void pmz_decoder_destroy(pmz_decoder* d) { delete d; }
PMZ_API int pmz_decoder_feed(pmz_decoder* d, const void* data, size_t size) {
  PMZ_TRY { return int(d->dec.feed(data, size)); }
  PMZ_CATCH_BAD_ALLOC { return PMZ_ERR_MEMORY; }
}
PMZ_API int pmz_decoder_finish(pmz_decoder* d) { return int(d->dec.finish()); }
PMZ_API int pmz_decoder_status(const pmz_decoder* d) { return int(d->dec.status()); }
PMZ_API const char* pmz_decoder_error(const pmz_decoder* d) {
  return d->dec.error_message().c_str();
}
PMZ_API uint64_t pmz_decoder_refine(pmz_decoder* d, uint64_t n) { return d->dec.refine(n); }
PMZ_API uint64_t pmz_decoder_coarsen(pmz_decoder* d, uint64_t n) { return d->dec.coarsen(n); }
PMZ_API void pmz_decoder_set_face_target(pmz_decoder* d, uint64_t f) { d->dec.set_face_target(f); }
PMZ_API uint64_t pmz_decoder_splits_applied(const pmz_decoder* d) {
  return d->dec.splits_applied();
}
PMZ_API uint64_t pmz_decoder_splits_available(const pmz_decoder* d) {
  return d->dec.splits_available();
}
PMZ_API uint64_t pmz_decoder_total_splits(const pmz_decoder* d) {
  return d->dec.info().total_splits;
}
PMZ_API uint32_t pmz_decoder_vertex_count(const pmz_decoder* d) { return d->dec.vertex_count(); }
PMZ_API uint32_t pmz_decoder_face_count(const pmz_decoder* d) { return d->dec.face_count(); }
PMZ_API const float* pmz_decoder_positions(const pmz_decoder* d) { return d->dec.positions(); }
PMZ_API const uint32_t* pmz_decoder_indices(const pmz_decoder* d) { return d->dec.indices(); }
PMZ_API const uint32_t* pmz_decoder_split_parents(const pmz_decoder* d) {
  return d->dec.split_parents();
}

PMZ_API void pmz_view_look_at(pmz_view* out, const float eye[3], const float target[3], float fov_y,
                              uint32_t width, uint32_t height, float near, float pixel_error) {
  const pmz::View v = pmz::look_at(eye, target, fov_y, width, height, near, pixel_error);
  std::copy_n(v.eye, 3, out->eye);
  std::copy_n(v.view_projection, 16, out->view_projection);
  out->fov_y = v.fov_y;
  out->viewport_height = v.viewport_height;
  out->pixel_error = v.pixel_error;
}
PMZ_API uint64_t pmz_decoder_update_view(pmz_decoder* d, const pmz_view* view,
                                         uint64_t max_splits) {
  pmz::View v;
  std::copy_n(view->eye, 3, v.eye);
  std::copy_n(view->view_projection, 16, v.view_projection);
  v.fov_y = view->fov_y;
  v.viewport_height = view->viewport_height;
  v.pixel_error = view->pixel_error;
  PMZ_TRY { return d->dec.update_view(v, max_splits); }
  PMZ_CATCH_BAD_ALLOC { return 0; }
}
PMZ_API void pmz_decoder_set_view_face_budget(pmz_decoder* d, uint64_t faces) {
  d->dec.set_view_face_budget(faces);
}
PMZ_API int pmz_decoder_view_complete(const pmz_decoder* d) { return d->dec.view_complete(); }
PMZ_API const uint32_t* pmz_decoder_nodes_to_fetch(const pmz_decoder* d, size_t* count) {
  const std::vector<uint32_t>& f = d->dec.nodes_to_fetch();
  *count = f.size();
  return f.data();
}
PMZ_API int pmz_decoder_node_range(const pmz_decoder* d, uint32_t k, uint64_t* offset,
                                   uint64_t* size) {
  return d->dec.node_range(k, *offset, *size);
}
PMZ_API int pmz_decoder_feed_node(pmz_decoder* d, uint32_t k, const void* data, size_t size) {
  PMZ_TRY { return int(d->dec.feed_node(k, data, size)); }
  PMZ_CATCH_BAD_ALLOC { return PMZ_ERR_MEMORY; }
}
PMZ_API uint32_t pmz_decoder_nodes_applied(const pmz_decoder* d) { return d->dec.nodes_applied(); }

PMZ_API uint32_t pmz_version(void) { return PMZ_VERSION_NUMBER; }

PMZ_API const char* pmz_status_name(int status) {
  if (status < PMZ_OK || status > PMZ_ERR_MEMORY) return "unknown";
  return pmz::status_name(pmz::Status(status));
}
PMZ_API uint64_t pmz_decoder_bytes_consumed(const pmz_decoder* d) {
  return d->dec.bytes_consumed();
}
PMZ_API void pmz_decoder_set_threads(pmz_decoder* d, uint32_t threads) {
  d->dec.set_threads(threads);
}
PMZ_API void pmz_decoder_set_split_target(pmz_decoder* d, uint64_t splits) {
  d->dec.set_split_target(splits);
}

PMZ_API void pmz_decoder_info(const pmz_decoder* d, pmz_stream_info* out) {
  const pmz::StreamInfo& i = d->dec.info();
  out->base_vertices = i.base_vertices;
  out->base_faces = i.base_faces;
  out->full_vertices = i.full_vertices;
  out->full_faces = i.full_faces;
  out->total_splits = i.total_splits;
  out->header_done = i.header_done;
  out->base_done = i.base_done;
  out->complete = i.complete;
  out->version_major = i.version_major;
  out->version_minor = i.version_minor;
  out->flags = i.flags;
  out->position_bits = i.position_bits;
  out->curvature = i.curvature;
  out->fine_curvature = i.fine_curvature;
  out->level = i.level;
  for (int k = 0; k < 3; ++k) {
    out->bbox_min[k] = i.bbox_min[k];
    out->bbox_max[k] = i.bbox_max[k];
  }
}

PMZ_API void pmz_decoder_changes(const pmz_decoder* d, pmz_changes* out) {
  const pmz::MeshChanges& c = d->dec.changes();
  out->vertex_begin = c.vertex_begin;
  out->face_begin = c.face_begin;
  out->modified_faces = c.modified_faces.data();
  out->modified_count = c.modified_faces.size();
  out->all = c.all;
  out->wedge_begin = c.wedge_begin;
}
PMZ_API void pmz_decoder_clear_changes(pmz_decoder* d) { d->dec.clear_changes(); }

PMZ_API uint32_t pmz_decoder_wedge_count(const pmz_decoder* d) { return d->dec.wedge_count(); }
PMZ_API const uint32_t* pmz_decoder_wedge_vertices(const pmz_decoder* d) {
  return d->dec.wedge_vertices();
}
PMZ_API const float* pmz_decoder_wedge_positions(const pmz_decoder* d) {
  return d->dec.wedge_positions();
}
PMZ_API const uint32_t* pmz_decoder_wedge_indices(const pmz_decoder* d) {
  return d->dec.wedge_indices();
}
PMZ_API uint32_t pmz_decoder_texcoord_set_count(const pmz_decoder* d) {
  return d->dec.texcoord_set_count();
}
PMZ_API const float* pmz_decoder_texcoords(const pmz_decoder* d, uint32_t set) {
  return d->dec.texcoords(set);
}
PMZ_API const float* pmz_decoder_normals(const pmz_decoder* d) { return d->dec.normals(); }
PMZ_API uint32_t pmz_decoder_color_components(const pmz_decoder* d) {
  return d->dec.color_components();
}
PMZ_API const float* pmz_decoder_colors(const pmz_decoder* d) { return d->dec.colors(); }
PMZ_API const uint32_t* pmz_decoder_face_materials(const pmz_decoder* d) {
  return d->dec.face_materials();
}
PMZ_API uint32_t pmz_decoder_material_count(const pmz_decoder* d) {
  return d->dec.material_count();
}
PMZ_API int pmz_decoder_material(const pmz_decoder* d, uint32_t i, pmz_material* out) {
  const pmz::MaterialInfo* m = d->dec.material(i);
  if (!m) return 0;
  out->name = m->name.c_str();
  out->base_color_texture = m->base_color_texture.c_str();
  out->normal_texture = m->normal_texture.c_str();
  for (int k = 0; k < 4; ++k) out->base_color[k] = m->base_color[k];
  return 1;
}

}  // extern "C"
