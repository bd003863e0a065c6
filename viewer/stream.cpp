// SPDX-License-Identifier: MIT
#include "stream.hpp"

#include <algorithm>

#include "pmz/app_support.hpp"

namespace pmzview {

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
  std::string error = source_->run(throttled(feed, options_.bytes_per_second, stop_), stop_);
  if (error.empty() && decode_error.empty() && !limit_reached && !stop_.load()) {
    std::lock_guard<std::mutex> lock(mutex);
    if (decoder.finish() != pmz::Status::ok) {
      decode_error = decoder.error_message();
      if (decode_error.empty()) decode_error = pmz::status_name(decoder.status());
    }
  }
  if (error.empty() && !decode_error.empty())
    error = pmz::app_support::stream_error(received_.load(), decode_error);
  error_ = error;
  done_ = true;  // publishes error_ (seq_cst store after the write)
}

}  // namespace pmzview
