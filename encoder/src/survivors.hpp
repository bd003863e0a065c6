// SPDX-License-Identifier: MIT
// Which input vertex each input vertex has become after a prefix of a collapse sequence: the one
// definition behind mesh_after() and the writer's base mesh.
#pragma once
#include <cstdint>
#include <numeric>
#include <vector>

#include "pmz/simplify.hpp"

namespace pmz {

// survivor[x] after the first k collapses: collapse i maps u to v, so following the chain from x
// ends at the vertex that stands for x. A face whose corners' survivors meet is one a collapse
// deleted. Every chain is resolved (path compression), so each lookup afterwards is one read.
inline std::vector<uint32_t> collapse_survivors(const CollapseSequence& seq, size_t k) {
  const uint32_t n = seq.mesh.vertex_count();
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  for (size_t i = 0; i < k && i < seq.collapses.size(); ++i)
    parent[seq.collapses[i].u] = seq.collapses[i].v;
  for (uint32_t x = 0; x < n; ++x) {
    uint32_t root = x;
    while (parent[root] != root) root = parent[root];
    for (uint32_t y = x; parent[y] != root;) {
      const uint32_t next = parent[y];
      parent[y] = root;
      y = next;
    }
  }
  return parent;
}

}  // namespace pmz
