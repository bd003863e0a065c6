// SPDX-License-Identifier: MIT
// pmz streaming decoder: C++ API (the C API, pmz/pmz.h, is a thin layer over it).
//
// Push model after zstd's ZSTD_decompressStream: feed() any slice of the .pmz byte stream
// (one byte or the whole file give the same result); decoded vertex splits become
// *available*; refine()/coarsen()/set_face_target() move the current mesh between the base
// mesh and the finest level available without re-reading bytes. The mesh is valid (a
// consistent indexed triangle mesh) after every call.
//
// Errors: an allocation failure in feed() or the level-of-detail calls becomes
// Status::out_of_memory (only the constructor throws std::bad_alloc); nothing is printed. status()
// and error_message() report an error until the decoder is destroyed: after one, feeding stops
// (feed() and finish() return it again) and the mesh stays valid at the level it had (the splits
// decoded before the error can still be applied). Each split's wedge and position are decoded when
// it is first applied, so refine(), set_face_target() and set_split_target() can also find damage
// (corrupt), reach the face limit (limit_exceeded) or run out of memory: check status() after them.
//
// Pointers and references returned point into the decoder; never free them. The mesh and
// attribute arrays, and changes().modified_faces, stay valid until the next call that changes
// the mesh (feed, refine, coarsen, set_face_target, set_split_target; clear_changes for the
// change report) or the decoder's destruction; moving a Decoder keeps them valid in the new
// owner. Arguments are not kept: feed() copies what it needs before returning.
//
// Threads: there is no global state. Different decoders may be used from different threads at
// the same time; one decoder must not be used from two threads at once (const member functions
// may run together, but not alongside a non-const one). version() and status_name() may be
// called from any thread.
//
// Depends on the standard library only. The version macros (PMZ_VERSION_MAJOR, ...) are in
// pmz/pmz.h, included here.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pmz/export.h"
#include "pmz/pmz.h"
#include "pmz/status.hpp"

namespace pmz {

// PMZ_VERSION_NUMBER of the library linked at run time (pmz_version() in C). Never fails.
PMZ_API uint32_t version();

struct DecoderLimits {
  // Hard caps, checked against header counts before any allocation.
  uint64_t max_vertices = 1ull << 27;
  uint64_t max_faces = 1ull << 28;
  uint64_t max_chunk_bytes = 1ull << 28;  // compressed or decompressed size of one chunk
};

struct StreamInfo {
  bool header_done = false;  // header parsed: the fields below are valid
  bool base_done = false;    // base mesh decoded: the mesh is drawable
  bool complete = false;     // end marker seen: every split is available
  uint32_t version_major = 0, version_minor = 0;
  uint32_t flags = 0;
  uint32_t position_bits = 0;  // 0 = lossless float32
  uint32_t curvature = 0;      // prediction offset weights, eighths (spec/format.md section 9.6)
  uint32_t fine_curvature = 0;
  uint32_t level = 0;  // compression level: 0 default, 1 speed (spec/format.md section 4)
  uint64_t base_vertices = 0, base_faces = 0;
  uint64_t full_vertices = 0, full_faces = 0;
  uint64_t total_splits = 0;
  float bbox_min[3] = {0, 0, 0}, bbox_max[3] = {0, 0, 0};
  uint64_t nodes = 0;  // independently decodable parts (spec/format.md section 15); 0: none
};

// What changed in the mesh buffers since the last clear_changes(), for uploading deltas.
struct MeshChanges {
  // Vertices [vertex_begin, vertex_count()) and faces [face_begin, face_count()) are new or
  // rewritten; vertex_begin == vertex_count() means none. After coarsening these shrink, so
  // a renderer simply draws face_count() faces.
  uint32_t vertex_begin = 0;
  uint32_t face_begin = 0;
  // Attribute wedges [wedge_begin, wedge_count()) are new. A face listed in modified_faces or at
  // or above face_begin has its wedge_indices() rewritten too (the two change together).
  uint32_t wedge_begin = 0;
  // Faces below face_begin whose indices were rewritten (may repeat; unsorted).
  std::vector<uint32_t> modified_faces;
  bool all = false;  // everything should be re-uploaded (e.g. first base mesh)
};

// A material as the file states it (OBJ's MTL, glTF's materials): carried, not interpreted.
struct MaterialInfo {
  std::string name;
  std::string base_color_texture;  // file name or URI (MTL map_Kd, glTF baseColorTexture)
  std::string normal_texture;      // MTL norm / map_Bump, glTF normalTexture
  float base_color[4] = {1, 1, 1, 1};
};

// What the ATTR chunks' symbols cost, in bits, per attribute kind (Decoder::count_attribute_bits).
struct AttributeBits {
  // wedges: which wedge each corner takes (seams, creases), shared by the kinds.
  enum Kind { texcoords, normals, colors, materials, wedges, kinds };
  double bits[kinds] = {};
};

// A camera, for view-dependent decoding (Decoder::update_view), in the mesh's own coordinates.
struct View {
  float eye[3] = {0, 0, 0};
  // Clip space from the mesh's coordinates (projection times view matrix; column-major, as
  // OpenGL and three.js keep them): nodes whose bounding sphere lies outside the frustum it
  // bounds are not refined.
  float view_projection[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float fov_y = 1.0471976f;         // vertical field of view, radians
  uint32_t viewport_height = 1080;  // pixels
  // Refine a node while its error bound would span more than this many pixels on screen (0:
  // every node in view, those that move nothing too).
  float pixel_error = 1;
  // Leave out the nodes whose normal cone faces away from the eye (spec/format.md section 15.5)
  // unless a node the view wants is their child: for closed surfaces (their backs hidden). False
  // for surfaces seen from behind (open ones, two-sided materials).
  bool cull_facing_away = true;
};

// A perspective view from `eye` towards `target` (y up) with a viewport of width x height
// pixels: View's fields from a look-at camera (an infinite far plane; near at `near`, > 0).
PMZ_API View look_at(const float eye[3], const float target[3], float fov_y, uint32_t width,
                     uint32_t height, float near, float pixel_error);

class PMZ_API Decoder {
 public:
  // Waits for the stream's first byte. `limits` cap the stream (checked against the header's
  // counts before any allocation; beyond them: limit_exceeded). May throw std::bad_alloc (the
  // C API's pmz_decoder_create returns NULL instead).
  explicit Decoder(const DecoderLimits& limits = {});
  ~Decoder();
  // A moved-from Decoder may only be destroyed or assigned to.
  Decoder(Decoder&&) noexcept;
  Decoder& operator=(Decoder&&) noexcept;
  Decoder(const Decoder&) = delete;
  Decoder& operator=(const Decoder&) = delete;

  // ---- input ----
  // Consumes the next `size` bytes (data may be null when size is 0). Returns ok or the
  // stream's first error; after an error further feeds read nothing and return it again.
  // Bytes after the end marker are ignored. May install the base mesh (the mesh changes).
  Status feed(const void* data, size_t size);
  // Call at end of input: truncated (and kept) if the end marker was not seen, else the
  // current status. The mesh and the splits decoded so far stay usable.
  Status finish();
  Status status() const;
  // One line ("pmz: corrupt stream: ... (chunk 3 at byte 1234)"), empty when ok.
  const std::string& error_message() const;
  // The header's fields (valid once header_done) and progress; all zero before the header.
  const StreamInfo& info() const;
  // Bytes fed while the status was ok, including those waiting for the rest of their chunk.
  uint64_t bytes_consumed() const;

  // Decoding threads for refine(), set_face_target() and set_split_target(): 0 (the default)
  // takes std::thread::hardware_concurrency(), 1 decodes on the calling thread only. With more,
  // the nodes of one level of a stream with a node table (spec/format.md section 15) whose bytes
  // all arrived are first applied on that many threads at once (streams without attributes; the
  // WebAssembly build always uses one). The result is the same for every count: mesh, ids, change
  // report and errors. Never fails; the threads live only during those calls.
  void set_threads(uint32_t n);

  // ---- view-dependent decoding (spec/format.md section 15) ----
  // A stream with a node table (info().nodes > 0) can be decoded node by node: update_view()
  // applies the nodes a view needs and undoes those it no longer needs, and a client that fetches
  // the stream by ranges feeds each node's bytes with feed_node() as they arrive, in any order.
  // Feed the stream in order up to the node table first (info().nodes becomes > 0 when its
  // NODE chunk arrived; node 0's chunks come before it). Streams without a node table, or with
  // attributes, or a decoder refined past node 0 with refine() before its first update_view(),
  // refine in file order instead (update_view() then refines what has arrived).
  //
  // Once update_view() applied a node past node 0, the mesh arrays hold the vertex and face ids
  // of every node up to the last one in file order applied so far: they grow when a later node
  // is applied (changes() reports the new ids from vertex_begin and face_begin on) and never
  // shrink; the ids of nodes not applied are unused vertices and degenerate faces (0, 0, 0),
  // which draw nothing. A view that needs only coarse nodes, which come first in file order,
  // holds their ids only. Every mix of
  // nodes that update_view() makes is a closed set under parents, so the mesh has no cracks:
  // it is the mesh that decoding those nodes in file order gives. From then on refine(),
  // coarsen(), set_face_target() and set_split_target() do nothing (return 0): the view decides.
  // changes() reports the rewritten and removed faces in modified_faces and the new vertices
  // from vertex_begin on.
  //
  // Where node k's bytes are in the stream (k >= 1; node 0's lie before the table): false
  // before the node table arrived or for k out of range. The ranges assume no chunk of an unknown
  // type between the nodes' chunks (a writer of this format writes none); otherwise feed_node()
  // refuses the bytes (corrupt) and the stream must be read in order.
  bool node_range(uint32_t k, uint64_t& offset, uint64_t& size) const;
  // Node k's bytes, exactly node_range(k)'s (framed chunks, checked: chunk checksums, the
  // node's split count and size). A node already arrived, or being fed in order by feed(), is
  // ignored (ok). An error fails the stream as feed() does (the mesh stays valid).
  Status feed_node(uint32_t k, const void* data, size_t size);
  // Moves the mesh towards `view`: undoes the nodes it no longer needs (descendants first), then
  // applies, largest projected error first, those it needs whose bytes have arrived and whose
  // parents are applied, whole nodes until about max_splits splits were applied or undone.
  // A node is needed when its bounding sphere meets the frustum and its error bound spans more
  // than view.pixel_error pixels, and so are its parents, whatever their own spheres and errors.
  // Returns the splits applied or undone.
  uint64_t update_view(const View& view, uint64_t max_splits = UINT64_MAX);
  // A face budget for the nodes update_view() applies, bounding the mesh's memory (0, the
  // default: none). From the next update_view() on, the view's nodes are taken largest projected
  // error first (file order among equals), each with its parents not yet taken: one that would
  // bring the faces past `faces` (BASE's, node 0's and the table's `faces` of every node taken)
  // is left out, and so are the nodes after it in that order that need it. The nodes needed are
  // those taken: nodes_to_fetch() lists only them, view_complete() is true once they are all
  // applied, and nodes applied that the budget no longer admits (a lower budget, another view)
  // are undone, descendants first. Node 0 is always applied, even past the budget. Then
  // face_count() less the degenerate faces of nodes not applied is at most `faces` once the
  // nodes left out are undone (at once with max_splits unbounded). The choice depends on the
  // view, the table and the budget only, not on what has arrived. Streams refined in file order
  // (see above) do not use it. Never fails.
  void set_view_face_budget(uint64_t faces);
  // After update_view(): whether every node the view needs (within the face budget) is applied
  // (for a stream refined in file order: whether all its splits are).
  bool view_complete() const;
  // After update_view(): the nodes the view needs (within the face budget) whose bytes have not
  // arrived, parents before children and the largest projected error first: what a client
  // fetches next.
  const std::vector<uint32_t>& nodes_to_fetch() const;
  uint32_t nodes_applied() const;  // nodes whose splits are in the mesh (node 0 included)

  // ---- level of detail ----
  // Each returns the number of splits applied / undone (fewer than asked when no more are
  // available or applied, or when an error stops it).
  uint64_t refine(uint64_t max_splits = UINT64_MAX);   // apply up to N available splits
  uint64_t coarsen(uint64_t max_splits = UINT64_MAX);  // undo up to N applied, the last first
  // Go to the smallest level whose face count >= faces (clamped to the base mesh and to what
  // is available).
  void set_face_target(uint64_t faces);
  // Go to the level with `splits` splits applied (clamped to those available).
  void set_split_target(uint64_t splits);
  uint64_t splits_applied() const;
  uint64_t splits_available() const;  // decoded so far: the finest level reachable now

  // ---- the current mesh ----
  // Float xyz per vertex, three uint32 indices per counter-clockwise face. Before the base
  // mesh: counts 0 and null arrays.
  uint32_t vertex_count() const;
  uint32_t face_count() const;
  const float* positions() const;
  const uint32_t* indices() const;
  // For geomorphs: the vertex each vertex was split from (UINT32_MAX for base vertices).
  // Valid for all vertices below vertex_count().
  const uint32_t* split_parents() const;

  // ---- attributes (format 8.0, spec/format.md section 14) ----
  // A render vertex is an attribute wedge: one combination of attribute values at one
  // position vertex (a vertex on a texture seam or normal crease has several). Without
  // attributes in the file (or before BASE): wedge_count() 0 and nullptr from the array
  // accessors. Arrays hold wedge_count() wedges and face_count() faces, have the lifetime of
  // the mesh arrays, and change only where changes() says.
  uint32_t wedge_count() const;
  const uint32_t* wedge_vertices() const;  // wedge -> position vertex index
  const float* wedge_positions() const;    // xyz per wedge: positions()[wedge_vertices()[w]]
  const uint32_t* wedge_indices() const;   // three wedges per face, the corners of indices()
  uint32_t texcoord_set_count() const;
  const float* texcoords(uint32_t set) const;  // u, v per wedge (nullptr for set >= count)
  const float* normals() const;                // xyz per wedge, unit length, or nullptr
  uint32_t color_components() const;           // 0, 3 (RGB) or 4 (RGBA)
  const float* colors() const;                 // color_components() per wedge, or nullptr
  // Materials: per face an index into the table (nullptr when the file has no materials; a
  // file with one material reports 0 for every face). The table is read once, with the
  // header: material() pointers and material_library() stay valid until destruction.
  const uint32_t* face_materials() const;
  uint32_t material_count() const;
  const MaterialInfo* material(uint32_t i) const;  // nullptr for i >= material_count()
  const std::string& material_library() const;     // OBJ mtllib name, or empty

  // ---- analysis (pmz-info) ----
  // Off unless count_attribute_bits() is called before the first feed(): then the decoder adds
  // what each ATTR symbol costs to into->bits as it decodes the symbol (the base ATTR chunk's in
  // feed(), a split's when the split is first applied), by the kind it codes; *into must outlive
  // that decoding. A symbol's cost is how far it narrowed the range decoder's interval (8 bits
  // per byte taken in, plus log2 of the range before over the range after); a chunk's costs add
  // up to its bytes but for the coder's start and end. Counting changes no decoded result.
  void count_attribute_bits(AttributeBits* into);

  // ---- changes, for partial uploads ----
  // What changed since the last clear_changes() (see MeshChanges).
  const MeshChanges& changes() const;
  // Starts a new change report (after the caller has uploaded the last one).
  void clear_changes();

 private:
  struct PMZ_LOCAL Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pmz
