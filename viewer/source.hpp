// SPDX-License-Identifier: MIT
// Byte sources for pmz-view: a file, stdin or an http(s) URL, read on the worker thread and
// optionally throttled to simulate a slow network.
#pragma once
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace pmzview {

// Receives the stream's bytes in order; returns false to stop reading.
using ByteSink = std::function<bool(const uint8_t* data, size_t size)>;

// Bytes [offset, offset + size) of the stream.
struct ByteRange {
  uint64_t offset = 0, size = 0;
};
// Receives range `index` of a read_ranges() call, all its bytes at once; false stops reading.
using RangeSink = std::function<bool(size_t index, const uint8_t* data, size_t size)>;

class Source {
 public:
  virtual ~Source() = default;
  // Reads to the end of the stream, until the sink returns false, or until stop is set.
  // Returns "" on success (including a requested stop), else a one-line error.
  virtual std::string run(const ByteSink& sink, const std::atomic<bool>& stop) = 0;
  // Stream size when known (file size, Content-Length), else 0. Set during run() for URLs.
  uint64_t total_bytes() const { return total_.load(std::memory_order_relaxed); }

  // Whether read_ranges() can work: a regular file or a URL (whose server may still ignore
  // Range). Stdin and pipes are read in order only.
  virtual bool ranged() const { return false; }
  // Reads the ranges (a URL several at once, with HTTP Range requests) and hands each to
  // `sink` whole, in the order they complete. A range reaching past the end is cut there.
  // A server that ignores Range and answers 200 with the whole body: that body goes to
  // `in_order` from byte 0 to its end, ranges_ignored() becomes true and the call returns
  // once it is read. "" on success or stop, else a one-line error.
  virtual std::string read_ranges(const std::vector<ByteRange>& ranges, const RangeSink& sink,
                                  const ByteSink& in_order, const std::atomic<bool>& stop);
  bool ranges_ignored() const { return ranges_ignored_.load(); }

 protected:
  std::atomic<uint64_t> total_{0};
  std::atomic<bool> ranges_ignored_{false};
};

// An http:// or https:// URL.
bool is_url(const std::string& spec);

// SOURCE is "-" (stdin), an http:// or https:// URL, or a path. Files are opened here so a bad
// path fails at once (null + error); a URL can only fail once run() connects.
std::unique_ptr<Source> open_source(const std::string& spec, std::string& error);

// Passes bytes on in small slices at no more than bytes_per_second (<= 0: unthrottled).
ByteSink throttled(ByteSink sink, double bytes_per_second, const std::atomic<bool>& stop);

}  // namespace pmzview
