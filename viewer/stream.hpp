// SPDX-License-Identifier: MIT
// The decode worker: reads a Source on its own thread and feeds the shared decoder, so the
// render thread never waits on IO. The decoder is not thread-safe; `mutex` guards it. The
// worker holds it only while feeding one slice (<= 64 KiB) or one node, the render thread
// while it refines within its per-frame budget and copies the changes out.
//
// View-dependent (StreamOptions::by_nodes, a file or URL): the worker reads in order, by
// ranges, up to the node table; then it fetches the ranges of the nodes the render thread's
// last Decoder::update_view() listed in nodes_to_fetch() and feeds them with feed_node(),
// until stopped (the node the in-order reading stopped in is read on in order instead). A stream
// without a node table (or with attributes) is read in order to its end; a server that ignores
// Range has its whole answer read in order.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <pmz/decoder.hpp>
#include <string>
#include <thread>

#include "source.hpp"

namespace pmzview {

struct StreamOptions {
  double bytes_per_second = 0;  // 0 = as fast as the source delivers
  uint64_t byte_limit = 0;      // stop after this many bytes (0 = read everything)
  bool by_nodes = false;        // fetch the nodes a view needs (see above)
};

class Stream {
 public:
  Stream() = default;
  ~Stream();  // stops and joins the worker
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;

  void start(std::unique_ptr<Source> source, const StreamOptions& options);
  void stop();

  std::mutex mutex;  // guards decoder
  pmz::Decoder decoder;

  uint64_t bytes_received() const { return received_.load(); }
  uint64_t bytes_total() const;               // 0 when unknown (stdin, no Content-Length)
  bool done() const { return done_.load(); }  // the worker has finished (any reason)
  // Valid once done(): "" or a one-line error (source failure or a decoder error).
  const std::string& error() const { return error_; }
  // Whether nodes are being fetched by ranges (the node table arrived; Range is honoured).
  bool fetching_nodes() const { return fetching_nodes_.load(); }

 private:
  void run();
  // The view-dependent reading (by_nodes); returns the source's error, "" otherwise. `feed`
  // feeds bytes in order, `pace` only waits for --rate.
  std::string run_by_ranges(const ByteSink& feed, const ByteSink& pace, std::string& decode_error,
                            bool& at_end);
  std::string fetch_nodes(const ByteSink& feed, const ByteSink& pace, uint64_t in_order,
                          std::string& decode_error, bool& at_end);

  std::unique_ptr<Source> source_;
  StreamOptions options_;
  std::thread thread_;
  std::atomic<uint64_t> received_{0};
  std::atomic<bool> done_{false};
  std::atomic<bool> stop_{false};
  std::atomic<bool> fetching_nodes_{false};
  std::string error_;
};

}  // namespace pmzview
