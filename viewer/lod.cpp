// SPDX-License-Identifier: MIT
#include "lod.hpp"

#include <chrono>

namespace pmzview {

namespace {

using clock = std::chrono::steady_clock;
// Splits per batch between clock checks: small enough to stay near the budget.
constexpr uint64_t kBatch = 256;

clock::time_point deadline_after(double budget_seconds) {
  return clock::now() + std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(
                            budget_seconds < 0 ? 1e6 : budget_seconds));
}

}  // namespace

uint64_t LodStepper::step_view(pmz::Decoder& decoder, const pmz::View& view,
                               double budget_seconds) {
  const auto deadline = deadline_after(budget_seconds);
  uint64_t moved = 0;
  settled_ = false;
  for (;;) {
    const uint64_t n = decoder.update_view(view, kBatch);
    moved += n;
    if (n == 0) break;
    if (clock::now() >= deadline) return moved;
  }
  settled_ = true;
  return moved;
}

uint64_t LodStepper::step(pmz::Decoder& decoder, const LodTarget& target, double budget_seconds) {
  const auto deadline = deadline_after(budget_seconds);
  // Within this many faces of the target one exact set_face_target() call is cheap.
  constexpr uint64_t kExactWindow = 4096;
  uint64_t moved = 0;
  settled_ = false;
  for (;;) {
    const uint64_t applied = decoder.splits_applied(), available = decoder.splits_available();
    if (target.follow) {
      if (applied >= available) break;
      moved += decoder.refine(kBatch);
    } else {
      const uint64_t faces = decoder.face_count();
      const uint64_t distance = faces > target.faces ? faces - target.faces : target.faces - faces;
      if (distance <= kExactWindow) {
        if (exact_faces_ != target.faces || exact_available_ != available) {
          decoder.set_face_target(target.faces);
          const uint64_t now_applied = decoder.splits_applied();
          moved += now_applied > applied ? now_applied - applied : applied - now_applied;
          exact_faces_ = target.faces;
          exact_available_ = available;
        }
        break;
      }
      if (faces < target.faces) {
        if (applied >= available) break;
        moved += decoder.refine(kBatch);
      } else {
        if (applied == 0) break;
        moved += decoder.coarsen(kBatch);
      }
    }
    if (decoder.splits_applied() == applied) break;  // no progress: nothing more to do
    if (clock::now() >= deadline) return moved;
  }
  settled_ = true;
  return moved;
}

}  // namespace pmzview
