// SPDX-License-Identifier: MIT
// bench-read-mesh: the reading stage of pmz-encode alone, its memory per step. Reads FILE into
// a polygon soup (read_polygon_soup), then repairs it into the indexed mesh (repair_mesh), and
// prints one JSON line: each step's seconds and its peak resident memory (VmHWM, reset through
// /proc/self/clear_refs before each step, so a step's peak counts what the steps before it left
// held), the peak of both (the process's VmHWM before any reset is not kept, so reading's peak
// is measured from the start), the soup's and the mesh's sizes. Uses the public meshio API only.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include "pmz/mesh.hpp"

namespace {

long status_kb(const char* key) {
  FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  const size_t n = std::strlen(key);
  while (std::fgets(line, sizeof line, f))
    if (std::strncmp(line, key, n) == 0) kb = std::strtol(line + n, nullptr, 10);
  std::fclose(f);
  return kb;
}

// Resets VmHWM to the current resident size (Linux 4.0 and later).
void reset_peak() {
  if (FILE* f = std::fopen("/proc/self/clear_refs", "w")) {
    std::fputs("5", f);
    std::fclose(f);
  }
}

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: bench-read-mesh FILE\n");
    return 2;
  }
  const std::string path = argv[1];
  pmz::PolygonSoup soup;
  std::string error;
  double t0 = now();
  if (!pmz::read_polygon_soup(path, soup, error)) {
    std::fprintf(stderr, "bench-read-mesh: %s\n", error.c_str());
    return 1;
  }
  const double read_s = now() - t0;
  const long read_peak = status_kb("VmHWM:"), soup_rss = status_kb("VmRSS:");
  reset_peak();
  pmz::IndexedMesh mesh;
  pmz::MeshRepairStats stats;
  t0 = now();
  const uint32_t soup_vertices = soup.vertex_count(), soup_faces = soup.face_count();
  pmz::repair_mesh(std::move(soup), mesh, stats);
  const double repair_s = now() - t0;
  const long repair_peak = status_kb("VmHWM:");
  std::printf(
      "{\"file\": \"%s\", \"soup_vertices\": %u, \"soup_faces\": %u, \"vertices\": %u, "
      "\"faces\": %u, \"read_s\": %.2f, \"read_peak_mb\": %.1f, \"soup_rss_mb\": %.1f, "
      "\"repair_s\": %.2f, \"repair_peak_mb\": %.1f, \"peak_mb\": %.1f}\n",
      path.c_str(), soup_vertices, soup_faces, mesh.vertex_count(), mesh.face_count(), read_s,
      read_peak / 1024.0, soup_rss / 1024.0, repair_s, repair_peak / 1024.0,
      std::max(read_peak, repair_peak) / 1024.0);
  return 0;
}
