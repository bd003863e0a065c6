// SPDX-License-Identifier: MIT
#include "stream.hpp"

#include <algorithm>
#include <chrono>

#include "pmz/app_support.hpp"

namespace pmzview {
namespace {

constexpr uint32_t kFlagAttributes = 1;  // HEAD flags bit 0 (spec/format.md section 14)
constexpr size_t kNodesPerBatch = 16;    // node ranges asked for at once

// `sink` after the first `skip` bytes: a whole body answered for a range, read in order from
// where the in-order reading had got to. `skipped` counts the bytes dropped.
ByteSink after(const ByteSink& sink, uint64_t skip, std::atomic<uint64_t>& skipped) {
  return [&sink, skip, &skipped, seen = uint64_t(0)](const uint8_t* data, size_t size) mutable {
    const size_t drop = size_t(std::min<uint64_t>(size, skip - std::min(skip, seen)));
    seen += size;
    skipped += drop;
    return drop == size || sink(data + drop, size - drop);
  };
}

}  // namespace

Stream::~Stream() { stop(); }

void Stream::start(std::unique_ptr<Source> source, const StreamOptions& options) {
  source_ = std::move(source);
  options_ = options;
  thread_ = std::thread([this] { run(); });
}

void Stream::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

uint64_t Stream::bytes_total() const {
  uint64_t total = source_ ? source_->total_bytes() : 0;
  if (options_.byte_limit && total) total = std::min(total, options_.byte_limit);
  return total;
}

void Stream::run() {
  std::string decode_error;
  bool limit_reached = false;
  ByteSink feed = [&](const uint8_t* data, size_t size) {
    if (options_.byte_limit) {
      uint64_t left = options_.byte_limit - received_.load();
      if (size >= left) {
        size = size_t(left);
        limit_reached = true;
      }
    }
    // Small slices keep the lock short: the render thread only try-locks.
    for (size_t at = 0; at < size;) {
      size_t n = std::min<size_t>(size - at, 64 * 1024);
      pmz::Status status;
      {
        std::lock_guard<std::mutex> lock(mutex);
        status = decoder.feed(data + at, n);
        if (status != pmz::Status::ok) decode_error = decoder.error_message();
      }
      received_ += n;
      at += n;
      if (status != pmz::Status::ok) {
        if (decode_error.empty()) decode_error = pmz::status_name(status);
        return false;
      }
    }
    return !limit_reached;
  };
  // --rate: the bytes in order, and a node's bytes before they are fed, on one clock.
  const ByteSink* paced_to = &feed;
  const ByteSink nowhere = [](const uint8_t*, size_t) { return true; };
  const ByteSink in_order =
      throttled([&](const uint8_t* data, size_t size) { return (*paced_to)(data, size); },
                options_.bytes_per_second, stop_);
  const ByteSink pace = [&](const uint8_t* data, size_t size) {
    paced_to = &nowhere;
    const bool go_on = in_order(data, size);
    paced_to = &feed;
    return go_on;
  };
  bool at_end = true;  // read to the end of the stream: the decoder is told so
  std::string error = options_.by_nodes && source_->ranged()
                          ? run_by_ranges(in_order, pace, decode_error, at_end)
                          : source_->run(in_order, stop_);
  if (error.empty() && decode_error.empty() && !limit_reached && at_end && !stop_.load()) {
    std::lock_guard<std::mutex> lock(mutex);
    if (decoder.finish() != pmz::Status::ok) {
      decode_error = decoder.error_message();
      if (decode_error.empty()) decode_error = pmz::status_name(decoder.status());
    }
  }
  if (error.empty() && !decode_error.empty())
    error = pmz::app_support::stream_error(received_.load(), decode_error);
  error_ = error;
  fetching_nodes_ = false;
  done_ = true;  // publishes error_ (seq_cst store after the write)
}

std::string Stream::run_by_ranges(const ByteSink& feed, const ByteSink& pace,
                                  std::string& decode_error, bool& at_end) {
  // In order up to the node table: small pieces first (the table is near the front), larger
  // ones for a stream that has none.
  uint64_t offset = 0, piece = 4096;
  const auto nodes_fetchable = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    const pmz::StreamInfo& info = decoder.info();
    return info.nodes > 0 && !(info.flags & kFlagAttributes);
  };
  while (!stop_.load()) {
    if (nodes_fetchable()) return fetch_nodes(feed, pace, offset, decode_error, at_end);
    const uint64_t total = source_->total_bytes();
    if (total && offset >= total) return "";  // the end of the stream
    bool short_piece = false, go_on = true;
    const RangeSink piece_in = [&](size_t, const uint8_t* data, size_t size) {
      offset += size;
      short_piece = size < piece;
      return go_on = feed(data, size);
    };
    const std::string error =
        source_->read_ranges({{offset, piece}}, piece_in, after(feed, offset, received_), stop_);
    if (!error.empty() || source_->ranges_ignored()) return error;  // (a whole body: at its end)
    if (!go_on || stop_.load()) break;  // a decoding error, the byte limit, or a stop
    if (short_piece) return "";
    piece = std::min<uint64_t>(2 * piece, 4 << 20);
  }
  at_end = false;
  return "";
}

std::string Stream::fetch_nodes(const ByteSink& feed, const ByteSink& pace, uint64_t in_order,
                                std::string& decode_error, bool& at_end) {
  at_end = false;
  fetching_nodes_ = true;
  std::vector<uint8_t> asked;  // per node: its range was asked for once
  uint32_t partial = 0;        // the node the in-order reading stopped in (0: none)
  std::vector<uint32_t> batch;
  std::vector<ByteRange> ranges;
  while (!stop_.load()) {
    batch.clear();
    ranges.clear();
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (decoder.status() != pmz::Status::ok) {  // (a node failed as it was applied)
        decode_error = decoder.error_message();
        return "";
      }
      asked.resize(size_t(decoder.info().nodes));
      for (uint32_t k : decoder.nodes_to_fetch()) {
        ByteRange r;
        if (k >= asked.size() || asked[k] || !decoder.node_range(k, r.offset, r.size)) continue;
        asked[k] = 1;
        if (r.offset < in_order && in_order < r.offset + r.size) {  // partly read in order
          partial = k;
          r = {in_order, r.offset + r.size - in_order};
        }
        batch.push_back(k);
        ranges.push_back(r);
        if (batch.size() == kNodesPerBatch) break;
      }
    }
    if (batch.empty()) {  // nothing to fetch for the last view: wait for the next
      std::this_thread::sleep_for(std::chrono::milliseconds(4));
      continue;
    }
    const RangeSink node_in = [&](size_t i, const uint8_t* data, size_t size) {
      if (batch[i] == partial) {  // the rest of the node the in-order reading stopped in
        const bool fed = feed(data, size) && decode_error.empty();
        in_order += fed ? size : 0;
        return fed;
      }
      if (!pace(data, size)) return false;
      pmz::Status status;
      {
        std::lock_guard<std::mutex> lock(mutex);
        status = decoder.feed_node(batch[i], data, size);
        if (status != pmz::Status::ok) decode_error = decoder.error_message();
      }
      received_ += size;
      return status == pmz::Status::ok;
    };
    const std::string error =
        source_->read_ranges(ranges, node_in, after(feed, in_order, received_), stop_);
    if (!error.empty()) return error;
    if (source_->ranges_ignored()) {  // the whole body was read in order: its end is reached
      at_end = true;
      return "";
    }
    if (!decode_error.empty()) return "";
  }
  return "";
}

}  // namespace pmzview
