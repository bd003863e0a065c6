// SPDX-License-Identifier: MIT
// The embedding loop that README.md shows ("Embedding the decoder"), compiled: the lines between
// the README markers must appear verbatim in README.md (ctest readme_loop_in_readme). read_some
// returns how many bytes it put into the buffer (0 at the end), upload takes the decoder and
// uploads what changes() reports, log takes a message.
#pragma once
#include <pmz/decoder.hpp>

template <class ReadSome, class Upload, class Log>
pmz::Decoder readme_loop(ReadSome read_some, Upload upload, Log log) {
  // README:begin
  pmz::Decoder dec;  // standard library only
  static char buf[65536];
  while (size_t n = read_some(buf, sizeof buf)) {  // any slicing gives the same result
    if (dec.feed(buf, n) != pmz::Status::ok) break;
    dec.refine(20000);  // per-frame budget of vertex splits
    upload(dec);        // dec.changes(): the vertices and faces to re-upload
    dec.clear_changes();
  }
  if (dec.finish() != pmz::Status::ok) log(dec.error_message());  // damaged or cut short
  while (dec.refine(20000) > 0) {  // the splits that arrived with the last reads
    upload(dec);
    dec.clear_changes();
  }
  // README:end
  return dec;
}
