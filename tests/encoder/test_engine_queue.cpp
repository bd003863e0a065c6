// SPDX-License-Identifier: MIT
// The collapse engine's queue after k collapses: every key it holds as current is the cost of its
// collapse recomputed from scratch on the mesh as it now is (spec/algorithm.md sections 2 and 5).
// The engine recomputes only what a collapse touches (terms of the 1-ring, torsion and keys of
// the 2-ring); a term left stale there shows in the output only where it changes the order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../../encoder/src/metric.hpp"
#include "pmz/simplify.hpp"
#include "simplify_test_meshes.hpp"

namespace {

const char* name(pmz::Metric m) {
  return m == pmz::Metric::qem ? "qem" : m == pmz::Metric::guarded ? "guarded" : "multifeature";
}

// A bumpy height field on an n x n grid: boundary vertices and curvature that varies, so that
// normal variation and torsion differ from vertex to vertex.
pmz::IndexedMesh bumpy_grid(uint32_t n) {
  pmz::IndexedMesh m = pmz_test::grid(n, 1.0 / n);
  for (size_t i = 0; i < m.positions.size(); i += 3) {
    const double x = m.positions[i], y = m.positions[i + 1];
    m.positions[i + 2] = float(0.15 * std::sin(7 * x) * std::cos(5 * y) + 0.05 * x * x);
  }
  return m;
}

struct Tally {
  size_t queued = 0, keys = 0, deferred = 0;
};

// The queue after k collapses: the cost of every queued collapse from the engine's cached terms
// is the cost from scratch; so is every key not marked stale (those are recomputed before use,
// by design); a key the guard penalised is at least its cost.
Tally expect_keys_current(const pmz::IndexedMesh& mesh, pmz::Metric metric, uint64_t k) {
  pmz::SimplifyOptions options;
  options.metric = metric;
  std::vector<pmz::detail::QueuedCollapse> queue;
  std::string error;
  Tally t;
  EXPECT_TRUE(pmz::detail::queued_collapses(mesh, options, k, queue, error)) << error;
  // The costs are in units of the mean input edge length (L^4 under the quadric): a relative
  // tolerance for the float rounding of terms summed in another order, and a floor for the
  // costs of flat collapses, zero up to that rounding.
  auto tolerance = [](float a, float b) {
    return 1e-4 * std::max(std::fabs(a), std::fabs(b)) + 1e-9;
  };
  for (const auto& q : queue) {
    SCOPED_TRACE(std::string(name(metric)) + " after " + std::to_string(k) +
                 " collapses: " + std::to_string(q.u) + " -> " + std::to_string(q.v));
    ++t.queued;
    EXPECT_NEAR(q.current, q.fresh, tolerance(q.current, q.fresh)) << "the engine's terms";
    if (q.key_stale) continue;
    if (q.deferred) {
      ++t.deferred;
      EXPECT_GE(q.cached, q.fresh - tolerance(q.cached, q.fresh));
    } else {
      ++t.keys;
      EXPECT_NEAR(q.cached, q.fresh, tolerance(q.cached, q.fresh)) << "the key";
    }
    if (::testing::Test::HasFailure()) break;  // one report is enough
  }
  return t;
}

TEST(EngineQueue, KeysAreTheCostsFromScratchAfterKCollapses) {
  const pmz::IndexedMesh meshes[] = {pmz_test::icosphere(3), pmz_test::torus(32, 16),
                                     bumpy_grid(24)};
  for (const auto& mesh : meshes) {
    for (auto metric : {pmz::Metric::multifeature, pmz::Metric::guarded, pmz::Metric::qem}) {
      Tally all;
      for (double fraction : {0.05, 0.2, 0.35}) {
        const Tally t = expect_keys_current(mesh, metric, uint64_t(mesh.face_count() * fraction));
        all.queued += t.queued, all.keys += t.keys, all.deferred += t.deferred;
        if (HasFailure()) return;
      }
      // The comparisons ran: a queue of hundreds, a good part of it keyed as current.
      EXPECT_GT(all.queued, mesh.vertex_count());
      EXPECT_GT(all.keys, mesh.vertex_count() / 5) << name(metric);
      if (metric == pmz::Metric::guarded) {
        EXPECT_GT(all.deferred, 0u);  // the guard held collapses back
      }
    }
  }
}

}  // namespace
