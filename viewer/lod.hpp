// SPDX-License-Identifier: MIT
// Moves the decoder's level of detail toward a target in bounded steps, so a big jump (e.g.
// base mesh to 1M faces) spreads over frames instead of stalling one.
#pragma once
#include <cstdint>
#include <pmz/decoder.hpp>

namespace pmzview {

struct LodTarget {
  bool follow = true;  // finest level available: refine as bytes arrive
  uint64_t faces = 0;  // otherwise: smallest level with at least this many faces
};

class LodStepper {
 public:
  // Applies/undoes splits until the target is met or `budget_seconds` has passed (< 0: no
  // limit). Returns the number of splits applied plus undone. Call with the decoder locked.
  uint64_t step(pmz::Decoder& decoder, const LodTarget& target, double budget_seconds);
  // Moves the mesh towards `view` (Decoder::update_view) in batches until it needs no more
  // or `budget_seconds` has passed (< 0: no limit). Returns the splits applied plus undone.
  uint64_t step_view(pmz::Decoder& decoder, const pmz::View& view, double budget_seconds);
  // True when the last step() left nothing to do for that target and the splits then available.
  bool settled() const { return settled_; }

 private:
  bool settled_ = false;
  // The exact set_face_target() call last made; repeating it would be a no-op.
  uint64_t exact_faces_ = UINT64_MAX, exact_available_ = UINT64_MAX;
};

}  // namespace pmzview
