// SPDX-License-Identifier: MIT
// The streaming decoder's refinement loop: decodes each split's wedge and position when it is
// first applied (their contexts come from the mesh), keeps what it decoded, and moves the mesh
// between levels with the shared ProgressiveMesh core (the chunks: decoder_stream.cpp; decoding
// for a view: decoder_view.cpp).
#include <atomic>
#if defined(__EMSCRIPTEN_PTHREADS__)
#include <pthread.h>
#endif
#include <system_error>
#include <thread>

#include "decoder_impl.hpp"

namespace pmz {

bool Decoder::Impl::apply() {
  Split& s = record.splits[level.applied];
  if (level.mesh.face_count() + 2ull > limits.max_faces) {
    fail(Status::limit_exceeded, "face limit reached while refining");
    return false;
  }
  if (level.applied <
      frontier.decoded) {  // applied before, on this very mesh state: no ring, no symbols
    const uint8_t side = record.sides[level.applied];
    level.mesh.resplit_listed(s.v, record.sector_corners.data() + level.sector_end, s.b, s.a,
                              side & kHasLeft, side & kHasRight);
    level.sector_end += s.b;
    if (attrs) attrs->reapply(level.mesh, level.applied, side & kHasLeft, side & kHasRight);
    note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
    ++level.applied;
    return true;
  }
  if (!first_apply(frontier, level.applied)) return false;
  level.sector_end += s.b;
  if (attrs && frontier.lazy_first == frontier.decoded) attrs->chunk_done();
  note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
  ++level.applied;
  // The last node's faces (the others' are checked as the next node starts). The split stands:
  // the mesh is valid, the stream is not.
  if (nodes.present && frontier.decoded == info.total_splits &&
      !node_counts_match(nodes.table.nodes.size() - 1)) {
    fail(Status::corrupt, "the last node added other faces or wedges than its table entry");
    return false;
  }
  return true;
}

// The first application of split i (f.decoded), by the serial frontier or a node's worker: its
// vertex, wedge and position symbols with contexts from f's mesh, the split, and what re-applying
// it needs. A failure leaves the mesh at the level before the split: the serial frontier refuses
// the split, a worker keeps the status and message for the merge.
bool Decoder::Impl::first_apply(Frontier& f, uint64_t i, bool resume) {
  Split& s = record.splits[i];
  ProgressiveMesh& mesh = *f.mesh;
  const bool serial = &f == &frontier;
  auto stop = [&](Status st, const std::string& what) {
    if (serial) return refuse(st, what);
    f.status = st;
    f.message = what;
    return false;
  };
  auto stop_split = [&](const char* what) {
    return stop(Status::corrupt, "split " + PMZ_DECIMAL(i) + what);
  };
  auto invalid = [&] { return stop_split(" has an invalid wedge"); };
  SplitChunkReader& reader = f.lazy.front();
  if (!resume) {
    if (i - f.lazy_first == reader.group_end()) {  // a group's first split: start its scan
      if (serial && nodes.present && nodes.applying < nodes.first_split.size() &&
          i == nodes.first_split[nodes.applying] && !start_node())
        return false;
      f.group_first = i;
      f.choice_ok = reader.begin_group(f.choice, mesh.vertex_count());
      f.find_vertices(scan_at_group_start(), record.splits);
    }
    if (s.v == kNoCorner) return stop_split(": vertex choice malformed");
    if (!mesh.gather_ring(s.v)) return invalid();
    if (nodes.present &&
        f.cells) {  // v's ring within the node's cell (spec/format.md section 15.4)
      bool inside = f.box.contains(&record.coords[size_t(s.v) * 3]);
      for (uint32_t w : mesh.ring())
        inside = inside && f.box.contains(&record.coords[size_t(w) * 3]);
      if (!inside) return stop_split(" reaches outside its node's cell");
    }
    {  // first application: the wedge symbols, with contexts from v's ring
      const uint32_t k = uint32_t(mesh.ring().size());
      // Ring walks cost the valence: bound their total (first applications; re-applying after
      // coarsening repeats the same work) so splits piling on one vertex cannot go quadratic.
      // (A worker counts from the total before its level: a lower bound, checked exactly as the
      // nodes are merged in file order.)
      f.ring_work += k;
      if (!serial) f.rings.push_back(k);
      if (f.ring_work >
          kRingWorkPerSplit * uint64_t(int64_t(i + 1) + f.ring_shift) + kRingWorkSlack)
        return stop(Status::limit_exceeded, kValences);
      // Decoded symbols cannot be put back: allocate what wedge_ranks needs before decoding them
      // (an allocation failure then leaves this split to retry, not a symbol lost).
      if (k > f.wedge_scratch_ring) {
        f.wedge_scratch.reserve(k);
        f.wedge_scratch_ring = k;
      }
      f.choice.reserve(k);
      // (About four sector corners per split on a regular mesh, valence 6: room for four per
      // split refine() made room for.)
      if (serial && record.sector_corners.capacity() - record.sector_corners.size() < k)
        record.sector_corners.reserve(
            std::max({2 * record.sector_corners.capacity(), record.sector_corners.size() + k,
                      4 * record.sides.capacity()}));
      if (attrs) attrs->reserve_split(mesh.face_count(), k);
      uint32_t count, rank;
      auto malformed = [&] { return stop_split(": wedge streams malformed"); };
      if (!reader.wedge_count(wedge_context(k, mesh.ring_closed()), count)) return malformed();
      if (info.level == kLevelSpeed) {  // the candidate's index (spec/format.md section 9.10)
        if (!reader.wedge_rank(rank_context(mesh.ring_closed(), false), rank)) return malformed();
        if (!speed_wedge_pick(mesh, count, rank, s.a, s.b)) return invalid();
      } else {
        if (!wedge_scores(record.coords.data(), f.choice.degrees(), s.v, mesh, count,
                          f.wedge_scratch))
          return invalid();
        if (!reader.wedge_rank(rank_context(mesh.ring_closed(), f.wedge_scratch.confident), rank))
          return malformed();
        if (!wedge_pick(mesh, count, rank, s.a, s.b, f.wedge_scratch)) return invalid();
      }
    }
    // A worker writes only within its node's face ids: beyond them it pauses, and the merge lets
    // it go on alone, as the serial decoder does (which finds a node that adds more faces than
    // its table entry where spec/format.md section 15 says).
    if (!serial && mesh.face_count() + uint64_t(s.a != kNoRank) + (s.b != kNoRank) > f.face_end)
      return !(f.paused = true);
  }
  const bool has_l = s.a != kNoRank, has_r = s.b != kNoRank;
  if (!mesh.split_gathered(s.v, s.a, s.b)) return invalid();
  {  // the position, then what re-applying the split needs
    PositionPrediction pred;
    int32_t residual[3], c[3];
    // (v's ring offsets: summed by the wedge scores over the same ring and coordinates.)
    const WedgeScratch& ws = f.wedge_scratch;
    bool decoded;
    if (info.level == kLevelSpeed) {
      speed_predict_position(record.coords.data(), mesh.u_ring(), pred);
      decoded = reader.speed_residuals(pred.context, residual);
    } else {
      predict_position(record.coords.data(), mesh.u_ring(), mesh.ring(), info.curvature,
                       info.fine_curvature, pred, ws.extent,
                       ws.ring_offsets_ok ? ws.ring_offsets : nullptr);
      decoded = reader.residuals(pred.context, pred.mix, residual);
    }
    if (!decoded) {
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(": residual streams malformed");
    }
    position_from_residuals(pred, residual, c);
    if (nodes.present && !f.box.contains(c)) {
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(" has u outside its node's cell");
    }
    f.grow_box(c);
    // Serially appended; a worker's vertex, split and face ids are within what was sized for
    // its level.
    const size_t u = mesh.vertex_count() - 1;
    auto put = [](auto& to, size_t at, auto x) {
      if (to.size() == at)
        to.push_back(x);
      else
        to[at] = x;
    };
    for (int a = 0; a < 3; ++a) {
      put(record.coords, u * 3 + a, c[a]);
      put(record.positions, u * 3 + a, quant.dequantize(c[a], a));
    }
    if (attrs &&
        !attrs->first_apply(mesh, record.coords.data(), record.positions.data(), has_l, has_r)) {
      record.coords.resize(record.coords.size() - 3);
      record.positions.resize(record.positions.size() - 3);
      mesh.undo_split(s.v, has_l, has_r);
      return stop_split(": attributes malformed");
    }
    put(record.parents, u, s.v);
    put(record.sides, i, uint8_t((has_l ? kHasLeft : 0) | (has_r ? kHasRight : 0)));
    // The vertex choice state (its umbrella sums need u's coordinates), then the group's
    // vertices kChoiceLag + 1 ahead (the lag: this split's ring is noted now).
    f.choice.applied(mesh, record.coords.data(), has_l, has_r);
    f.find_vertices(scan_after_split(uint32_t(i - f.group_first)), record.splits);
    s.a = mesh.sector_hint();
    s.b = uint32_t(mesh.sector_faces().size());
    for (uint32_t n : mesh.sector_corners())
      (serial ? record.sector_corners : f.sectors).push_back(n);  // (serially: reserved above)
    if (++f.decoded - f.lazy_first == reader.split_count()) {
      f.lazy_first = f.decoded;
      f.lazy.pop_front();  // its bytes are no longer needed
    }
  }
  return true;
}

// A worker's first applications up to split `last` or its first failure (decoding a node for a
// view): here, with the refinement loop's code, not with the once-per-node code around it.
void Decoder::Impl::first_apply_worker(Frontier& w, uint64_t last) {
  while (w.decoded < last && !w.lazy.empty()) {
    const uint64_t ahead = w.decoded + FanPrefetcher::kWalkers;
    w.fans.step(level.mesh, record.coords.data(), record.coords.size(),
                ahead < last ? record.splits[ahead].v : kNoCorner, frontier.choice.degrees(),
                frontier.choice.sums_bytes());
    if (!first_apply(w, w.decoded)) break;
  }
}

// Several nodes of one level whose bytes all arrived, at once (threads > 1, a stream with nodes
// and without attributes, at a node's start): each on a worker with its own view of the mesh and
// vertex choice, writing the vertex, face and split ids the table gives it (nodes of a level touch
// disjoint state). Then merged in file order as the serial decoder would have applied them: the
// first failure (the worker's own, the ring work bound, a node's face count) ends the applied
// prefix there, the splits after it are undone and the serial error reported. Returns the splits
// applied (0: nothing to run in parallel here; the serial path goes on).
uint64_t Decoder::Impl::parallel_nodes(uint64_t max_splits, uint64_t face_target) {
#if defined(__wasm__) && !defined(__EMSCRIPTEN_PTHREADS__)
  (void)max_splits, (void)face_target;
  return 0;
#else
  const size_t k = nodes.applying, total = nodes.table.nodes.size();
  if (threads < 2 || !nodes.present || attrs || stage == Stage::failed || k < 1 || k >= total ||
      level.applied != frontier.decoded || level.applied != nodes.first_split[k] ||
      !node_counts_match(k - 1))
    return 0;
  const std::vector<NodeEntry>& table = nodes.table.nodes;
  const uint32_t lv = table[k].level;
  if (nodes.table.levels[lv].side == 0) return 0;
  const uint64_t v0 = level.mesh.vertex_count(), f0 = level.mesh.face_count(), s0 = level.applied;
  // The level's nodes from k on that arrived whole and that the serial decoder would apply
  // whole within the targets (their table faces below face_target and the face limit).
  size_t end = k;
  uint64_t faces = f0;
  while (end < total && end < nodes.arriving && table[end].level == lv &&
         nodes.first_split[end] + table[end].splits - s0 <= max_splits &&
         faces + table[end].faces < face_target &&
         faces + table[end].faces + 2 <= limits.max_faces &&
         faces + table[end].faces <= info.full_faces)
    faces += table[end++].faces;
  if (end - k < 2) return 0;
  const uint64_t s1 = end < total ? nodes.first_split[end] : info.total_splits;
  const uint64_t v1 = v0 + (s1 - s0);
  if (v1 > info.full_vertices) return 0;
  std::vector<std::unique_ptr<Frontier> > work;
  std::vector<uint64_t> face_start;
  // Models per thread, the first node's copied in at each node it takes (the nodes' own group
  // models are not used again: their chunks all arrived); back to the spares at the end.
  std::vector<std::unique_ptr<SplitModels> > thread_models;
  PMZ_TRY {
    // Room for every id the workers write: the owner's arrays sized to the level's end.
    resize_level(faces, v1, s1);
    if (k == 1) nodes.first_models = std::move(nodes.models[0]);
    drop_models(k - 1);  // its splits are all decoded
    for (size_t t = std::min<size_t>(threads, end - k); t--;)
      thread_models.push_back(first_models_copy());
    if (nodes.bins_level != int64_t(lv)) {
      nodes.bins.build(nodes.table, lv, record.coords.data(), uint32_t(v0));
      nodes.bins_level = lv;
    }
    uint32_t epoch = frontier.choice.take_epochs(s1 - s0 + (end - k));
    uint64_t at = f0;
    for (size_t j = k; j < end; ++j) {
      Frontier& w = *work.emplace_back(std::make_unique<Frontier>());
      start_worker(w, j, uint32_t(v0 + nodes.first_split[j] - s0), at, epoch,
                   nodes.bins.take(uint32_t(j)), frontier.ring_work);
      epoch += uint32_t(table[j].splits + 1);
      for (uint64_t got = 0; got < table[j].splits; frontier.lazy.pop_front()) {
        got += frontier.lazy.front().split_count();
        w.lazy.push_back(std::move(frontier.lazy.front()));
      }
      face_start.push_back(at);
      at += table[j].faces;
    }
  }
  PMZ_CATCH_BAD_ALLOC {  // (the readers may be gone: refused like any split out of memory)
    resize_level(f0, v0, s0);
    refuse(Status::out_of_memory, "allocation failed while refining");
    return 0;
  }
  frontier.lazy_first = s1;
  // The workers take the nodes in file order.
  std::atomic<size_t> next{0}, slot{0};
  auto go = [&](size_t j, bool resume, SplitModels* m) {
    Frontier& w = *work[j];
    PMZ_TRY {
      if (!resume) {
        *m = *nodes.first_models;
        for (SplitChunkReader& r : w.lazy) r.set_models(*m);
      }
      const uint64_t last = nodes.first_split[k + j] + table[k + j].splits;
      if (resume && !first_apply(w, w.decoded, true)) return;
      for (;;) {  // (the fans ahead, as prefetch(): within the node's cell)
        const uint64_t ahead = w.decoded + FanPrefetcher::kWalkers;
        w.fans.step(level.mesh, record.coords.data(), record.coords.size(),
                    ahead < last ? record.splits[ahead].v : kNoCorner, frontier.choice.degrees(),
                    frontier.choice.sums_bytes());
        if (w.decoded >= last || !first_apply(w, w.decoded)) break;
      }
      if (w.paused && !resume) {  // the merge resumes it: its models kept
        nodes.models[k + j] = std::make_unique<SplitModels>(*m);
        for (SplitChunkReader& r : w.lazy) r.set_models(*nodes.models[k + j]);
      }
    }
    PMZ_CATCH_BAD_ALLOC {
      w.paused = false;
      w.status = Status::out_of_memory;
      w.message = "allocation failed while refining";
    }
  };
  auto run = [&] {  // (one call per thread: a models object each)
    SplitModels* m = thread_models[slot++].get();
    for (size_t j; (j = next++) < work.size();) go(j, false, m);
  };
  {
#if defined(__EMSCRIPTEN_PTHREADS__)
    // The threaded WebAssembly module (scripts/web.sh): pthread_create fails once the pool of
    // web workers made at load is in use (PTHREAD_POOL_SIZE_STRICT=2) and this thread runs the
    // rest; without exceptions compiled in, std::thread would abort there instead.
    std::vector<pthread_t> pool;
    auto entry = [](void* f) -> void* {
      (*static_cast<decltype(run)*>(f))();
      return nullptr;
    };
    for (uint32_t t = 1; t < std::min<size_t>(threads, work.size()); ++t) {
      pthread_t id;
      if (pthread_create(&id, nullptr, entry, &run) != 0) break;
      pool.push_back(id);
    }
    run();
    for (pthread_t id : pool) pthread_join(id, nullptr);
#else
    std::vector<std::jthread> pool;
    try {  // (fewer threads if the system has none to give: this one runs the rest)
      for (uint32_t t = 1; t < std::min<size_t>(threads, work.size()); ++t) pool.emplace_back(run);
    } catch (const std::system_error&) {
    }
    run();
#endif
  }
  for (std::unique_ptr<SplitModels>& m : thread_models) spare_models(m);
  // The merge: where the serial decoder would have stopped (stop, with its error).
  uint64_t stop = s1, work_sum = frontier.ring_work;
  Status st = Status::ok;
  std::string what;
  for (size_t j = 0; j < work.size() && st == Status::ok; ++j) {
    Frontier& w = *work[j];
    const uint64_t first = nodes.first_split[k + j];
    if (w.paused) {  // the nodes after it undone, it goes on alone, with room for its faces
      for (size_t x = j + 1; x < work.size(); ++x) {
        Frontier& o = *work[x];
        undo_worker(o, nodes.first_split[k + x]);
        o.decoded = nodes.first_split[k + x];
        o.rings.clear();
        o.status = Status::ok;
        o.paused = false;
      }
      const uint64_t room = w.view.face_count() + 2 * (first + table[k + j].splits - w.decoded);
      if (room * 3 > level.mesh.corner_vertex.size()) {
        level.mesh.corner_vertex.resize(room * 3);
        level.mesh.opposite.resize(room * 3);
      }
      w.paused = false;
      w.face_end = UINT64_MAX;
      go(j, true, nullptr);
    }
    for (size_t t = 0; t < w.rings.size(); ++t) {
      work_sum += w.rings[t];
      if (work_sum > kRingWorkPerSplit * (first + t + 1) + kRingWorkSlack) {
        stop = first + t, st = Status::limit_exceeded, what = kValences;
        break;
      }
    }
    if (st != Status::ok) break;
    if (w.status != Status::ok) {
      stop = w.decoded, st = w.status, what = w.message;
    } else if (k + j + 1 < end && w.view.face_count() != w.face_end) {
      stop = nodes.first_split[k + j + 1], st = Status::corrupt;
      what = "node " + PMZ_DECIMAL(k + j) + " added other faces or wedges than its table entry";
    }
    frontier.ring_work = work_sum;
  }
  // Undo what lies past stop (nodes touch disjoint state: in any node order), then take the
  // prefix over: sizes, sector lists, the change report, the box.
  uint64_t f_end = f0;
  for (size_t j = 0; j < work.size(); ++j) {
    Frontier& w = *work[j];
    undo_worker(w, std::max(stop, nodes.first_split[k + j]));
    if (nodes.first_split[k + j] >= stop) continue;
    f_end = w.view.face_count();
    uint64_t faces_now = face_start[j], corners = 0;
    for (uint64_t t = nodes.first_split[k + j]; t < std::min(w.decoded, stop); ++t) {
      const Split& x = record.splits[t];
      faces_now += new_faces(record.sides[t]);
      note_rewritten<3>({w.sectors.data() + corners, x.b}, faces_now);
      corners += x.b;
    }
    record.sector_corners.insert(record.sector_corners.end(), w.sectors.begin(),
                                 w.sectors.begin() + ptrdiff_t(corners));
    level.sector_end += corners;
    if (j) drop_models(k + j - 1);
    nodes.start_faces = face_start[j];
    nodes.applying = k + j + 1;
  }
  const uint64_t v_end = v0 + (stop - s0);
  resize_level(f_end, v_end, stop);
  for (uint64_t x = v0; x < v_end; ++x) frontier.grow_box(&record.coords[x * 3]);
  frontier.decoded = level.applied = stop;
  if (st != Status::ok) {
    refuse(st, what);
  } else if (end == total && !node_counts_match(total - 1)) {
    fail(Status::corrupt, "the last node added other faces or wedges than its table entry");
    return stop - s0 - 1;  // (as apply(): the last split stands but is not counted)
  }
  return stop - s0;
#endif
}

void Decoder::Impl::undo() {
  // undo_resplit may throw bad_alloc only from its scratch, before it changes anything: count
  // the split as undone only after it.
  const uint8_t side = record.sides[level.applied - 1];
  const Split& s = record.splits[level.applied - 1];
  level.mesh.undo_resplit(s.v, s.a, s.b, side & kHasLeft, side & kHasRight);
  level.sector_end -= s.b;
  --level.applied;
  if (attrs) {
    attrs->undo(level.mesh, level.applied, side & kHasLeft, side & kHasRight);
    level.changes.wedge_begin = std::min(level.changes.wedge_begin, attrs->state.wedge_count);
  }
  level.changes.face_begin = std::min(level.changes.face_begin, level.mesh.face_count());
  level.changes.vertex_begin = std::min(level.changes.vertex_begin, level.mesh.vertex_count());
  note_rewritten(level.mesh.sector_faces(), level.mesh.face_count());
}

uint64_t Decoder::Impl::refine(uint64_t max_splits, uint64_t face_target) {
  uint64_t n = 0;
  if (sel.on) return 0;  // the view decides (update_view)
  PMZ_TRY {
    // Room for every split this call may apply (bounded by decoded input, not the header):
    // apply() must not grow a buffer once it changed the mesh (an allocation failure there would
    // leave a split half applied). With a face target, at most the missing faces (a split adds
    // at least one).
    uint64_t want = std::min(max_splits, record.available - level.applied);
    want = std::min(want, face_target - std::min<uint64_t>(face_target, level.mesh.face_count()));
    uint64_t target = level.applied + want;
    if (target > level.applied) {
      // Grown geometrically: at least to the next power of two and at least doubled. Reserving
      // exactly `target`, or all that is available, reallocates (and copies everything) on every
      // small call or every chunk that arrives (a viewer refining a few hundred per frame; a
      // stream refined as it arrives: 1.2M faces in 47 chunks took 3.3x the CPU time). Below
      // twice `target`, so still bounded by the decoded input. Once `target` is at least
      // 1 / kHeaderTrust of the header's split count, room for all of them at once: the
      // doublings up to there copied every buffer and faulted its pages in again (1.2M faces fed
      // in 997-byte slices with refine(5000) after each: about a quarter of the CPU time), and
      // the reservation stays within kHeaderTrust times the decoded input (untouched capacity
      // costs no memory until used).
      const uint64_t capacity = record.sides.capacity();
      uint64_t room =
          target <= capacity ? target
          : header_trusted(target)
              ? std::max(target, info.total_splits)
              : std::max(target, std::min<uint64_t>(info.total_splits,
                                                    std::max(std::bit_ceil(target), 2 * capacity)));
      uint64_t nv = info.base_vertices + room;
      level.mesh.reserve(nv, level.mesh.face_count() + 2 * (room - level.applied));
      record.coords.reserve(nv * 3);
      record.positions.reserve(nv * 3);
      record.parents.reserve(nv);
      record.sides.reserve(room);
      if (attrs)
        attrs->reserve(level.mesh.face_count() + 2 * (room - level.applied), room,
                       info.total_splits);
      frontier.choice.reserve_vertices(nv);
    }
    level.fans.reset();
    level.listed_ahead = 0;
    while (n < max_splits && level.applied < record.available &&
           level.mesh.face_count() < face_target) {
      // (A batch refused at its first split applied none: the loop's test then ends it.)
      const uint64_t m = parallel_nodes(max_splits - n, face_target);
      if (m || level.applied >= record.available) {
        n += m;
        level.fans.reset();
        continue;
      }
      prefetch();
      if (!apply()) break;
      ++n;
    }
  }
  PMZ_CATCH_BAD_ALLOC { fail(Status::out_of_memory, "allocation failed while refining"); }
  return n;
}

uint64_t Decoder::Impl::coarsen(uint64_t max_splits, uint64_t face_floor) {
  uint64_t n = 0;
  if (sel.on) return 0;
  level.fans.reset();
  UnlinkWindow window;
  PMZ_TRY {
    for (; n < max_splits && level.applied > 0; ++n) {
      const uint8_t side = record.sides[level.applied - 1];
      if (level.mesh.face_count() - (side & kHasLeft ? 1u : 0u) - (side & kHasRight ? 1u : 0u) <
          face_floor)
        break;
      // Splits are undone last first: the sector of the one kWalkers further on, and further
      // still what unlinking its new faces touches (see prefetch_unlink).
      constexpr uint32_t kAhead = FanPrefetcher::kWalkers;
      if (level.applied > kAhead)
        level.fans.step_sector(level.mesh, record.splits[level.applied - 1 - kAhead].a,
                               record.splits[level.applied - 1 - kAhead].b);
      else
        level.fans.step_sector(level.mesh, kNoCorner, 0);
      prefetch_unlink(window);
      undo();
    }
  }
  PMZ_CATCH_BAD_ALLOC {  // undo_resplit grows no scratch in practice (see its test);
                         // kept as a guard
    fail(Status::out_of_memory, "allocation failed while coarsening");
  }
  // The undone splits lowered face_begin: faces listed before then may now be at or above it
  // (rewritten again from there on, or removed). MeshChanges lists only faces below it.
  if (n > 0)
    std::erase_if(level.changes.modified_faces,
                  [&](uint32_t f) { return f >= level.changes.face_begin; });
  return n;
}

uint64_t Decoder::refine(uint64_t max_splits) { return impl_->refine(max_splits, UINT64_MAX); }
uint64_t Decoder::coarsen(uint64_t max_splits) { return impl_->coarsen(max_splits, 0); }

void Decoder::set_face_target(uint64_t faces) {
  Impl& d = *impl_;
  d.coarsen(UINT64_MAX, faces);  // the coarsest level still holding `faces`
  d.refine(UINT64_MAX, faces);   // or refine until it does
}

void Decoder::set_split_target(uint64_t splits) {
  Impl& d = *impl_;
  if (splits < d.level.applied)
    coarsen(d.level.applied - splits);
  else
    refine(splits - d.level.applied);
}

uint64_t Decoder::splits_applied() const {
  return impl_->level.applied + impl_->sel.applied_splits;
}
uint64_t Decoder::splits_available() const {
  return impl_->sel.on ? impl_->sel.available : impl_->record.available;
}
uint32_t Decoder::vertex_count() const { return impl_->level.mesh.vertex_count(); }
uint32_t Decoder::face_count() const { return impl_->level.mesh.face_count(); }
const float* Decoder::positions() const {
  return impl_->record.positions.empty() ? nullptr : impl_->record.positions.data();
}
const uint32_t* Decoder::indices() const {
  return impl_->level.mesh.corner_vertex.empty() ? nullptr : impl_->level.mesh.corner_vertex.data();
}
const uint32_t* Decoder::split_parents() const {
  return impl_->record.parents.empty() ? nullptr : impl_->record.parents.data();
}
const MeshChanges& Decoder::changes() const { return impl_->level.changes; }
void Decoder::clear_changes() {
  Impl& d = *impl_;
  d.level.changes.all = false;
  d.level.changes.modified_faces.clear();
  d.level.changes.vertex_begin = d.level.mesh.vertex_count();
  d.level.changes.face_begin = d.level.mesh.face_count();
  d.level.changes.wedge_begin = d.attrs ? d.attrs->state.wedge_count : 0;
}

// Attributes: nothing (0 / nullptr) without them, and before the base ATTR chunk.
uint32_t Decoder::wedge_count() const {
  const Impl& d = *impl_;
  return d.attrs && d.info.base_done ? d.attrs->state.wedge_count : 0;
}
const uint32_t* Decoder::wedge_vertices() const {
  return wedge_count() ? impl_->attrs->state.wedge_vertex.data() : nullptr;
}
const float* Decoder::wedge_positions() const {
  return wedge_count() ? impl_->attrs->wedge_positions.data() : nullptr;
}
const uint32_t* Decoder::wedge_indices() const {
  return wedge_count() ? impl_->attrs->state.corner_wedge.data() : nullptr;
}
uint32_t Decoder::texcoord_set_count() const {
  return wedge_count() ? impl_->attrs->state.head.texcoord_sets : 0;
}
const float* Decoder::texcoords(uint32_t set) const {
  return set < texcoord_set_count() ? impl_->attrs->texcoords[set].data() : nullptr;
}
const float* Decoder::normals() const {
  return wedge_count() && impl_->attrs->state.head.normals ? impl_->attrs->normals.data() : nullptr;
}
uint32_t Decoder::color_components() const {
  return wedge_count() ? impl_->attrs->state.head.color_components : 0;
}
const float* Decoder::colors() const {
  return color_components() ? impl_->attrs->colors.data() : nullptr;
}
const uint32_t* Decoder::face_materials() const {
  const Impl& d = *impl_;
  return d.attrs && d.info.base_done && !d.attrs->state.face_material.empty()
             ? d.attrs->state.face_material.data()
             : nullptr;
}
uint32_t Decoder::material_count() const { return uint32_t(impl_->materials.size()); }
const MaterialInfo* Decoder::material(uint32_t i) const {
  return i < impl_->materials.size() ? &impl_->materials[i] : nullptr;
}
const std::string& Decoder::material_library() const {
  static const std::string kNone;
  return impl_->attrs ? impl_->attrs->state.head.material_library : kNone;
}

// The public kinds are the codec's, in the same order.
static_assert(int(AttributeBits::texcoords) == AttributeCost::kTexcoords &&
              int(AttributeBits::normals) == AttributeCost::kNormals &&
              int(AttributeBits::colors) == AttributeCost::kColors &&
              int(AttributeBits::materials) == AttributeCost::kMaterials &&
              int(AttributeBits::wedges) == AttributeCost::kWedges &&
              int(AttributeBits::kinds) == AttributeCost::kKinds);
void Decoder::count_attribute_bits(AttributeBits* into) {
  impl_->attribute_bits = into ? into->bits : nullptr;
}

}  // namespace pmz
