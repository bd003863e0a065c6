// SPDX-License-Identifier: MIT
// A C++ program that links the installed pmz (static or shared decoder) and decodes a .pmz file
// (argv[1]) through the README's embedding loop, reading SLICE bytes at a time (argv[2]): it must
// end at the full mesh, with every index in range and the change report covering the mesh.
#include <cstdio>
#include <cstdlib>
#include <pmz/decoder.hpp>
#include <string>

#include "readme_loop.hpp"

int main(int argc, char** argv) {
  if (argc < 3) return 2;
  FILE* f = std::fopen(argv[1], "rb");
  if (!f) return 1;
  const size_t slice = std::strtoul(argv[2], nullptr, 10);
  uint64_t uploads = 0, changed_faces = 0;
  std::string logged;
  pmz::Decoder dec = readme_loop(
      [&](char* buf, size_t size) { return std::fread(buf, 1, size < slice ? size : slice, f); },
      [&](const pmz::Decoder& d) {
        ++uploads;
        changed_faces += d.face_count() - d.changes().face_begin;
      },
      [&](const std::string& message) { logged = message; });
  std::fclose(f);
  const pmz::StreamInfo& info = dec.info();
  bool ok = dec.status() == pmz::Status::ok && logged.empty() && info.complete &&
            dec.splits_applied() == info.total_splits && dec.face_count() == info.full_faces &&
            dec.vertex_count() == info.full_vertices && changed_faces >= dec.face_count();
  for (uint64_t i = 0; ok && i < uint64_t(dec.face_count()) * 3; ++i)
    ok = dec.indices()[i] < dec.vertex_count();
  std::printf("consumer: %u vertices, %u faces of %llu after %llu uploads (%s)\n",
              dec.vertex_count(), dec.face_count(), (unsigned long long)info.full_faces,
              (unsigned long long)uploads, logged.empty() ? "ok" : logged.c_str());
  pmz::Decoder junk;
  const char bytes[] = "not a pmz stream";
  ok = ok && pmz::version() == PMZ_VERSION_NUMBER;  // the installed header's and library's
  ok = ok && junk.feed(bytes, sizeof bytes) == pmz::Status::bad_magic &&
       !junk.error_message().empty() && pmz::status_name(junk.status()) != nullptr;
  return ok ? 0 : 1;
}
