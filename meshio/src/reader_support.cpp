// SPDX-License-Identifier: MIT
// The format readers' shared parts (reader_support.hpp): file reading, error messages,
// vertex welding.
#include "reader_support.hpp"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <unordered_map>
#include <vector>

namespace pmz {

std::FILE* open_file(const std::string& path, std::string& error) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = path + ": no such file";
    return nullptr;
  }
  if (std::filesystem::is_directory(path, ec)) {
    error = path + ": is a directory, not a mesh file";
    return nullptr;
  }
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) error = path + ": cannot open: " + std::strerror(errno);
  return f;
}

bool read_file(const std::string& path, std::string& data, std::string& error) {
  std::FILE* f = open_file(path, error);
  if (!f) return false;
  data.clear();
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
  bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) {
    error = path + ": read error";
    return false;
  }
  if (data.empty()) {
    error = path + ": empty file";
    return false;
  }
  return true;
}

ByteSource::ByteSource(std::FILE* file, uint64_t size, size_t window,
                       std::function<void(double)> progress)
    : size_(size),
      file_(file),
      start_(std::ftell(file)),
      window_(std::max<size_t>(window, 1)),
      progress_(std::move(progress)),
      spilled_(nullptr, &std::fclose) {}

std::string_view ByteSource::fill(size_t n) {
  if (!file_ || eof_) return view();
  // What is left of the window moves to its front; the rest is read anew.
  const size_t kept = end_ - pos_;
  if (pos_ > 0) std::memmove(buffer_.data(), buffer_.data() + pos_, kept);
  base_ += pos_, pos_ = 0, end_ = kept;
  if (buffer_.size() < std::max(n, window_))
    buffer_.resize(std::max({n, window_, buffer_.size() * 2}));
  // A short read is retried: only the end of the file or an error ends the source (a read
  // interrupted by a signal is retried too).
  while (end_ < n && !eof_) {
    errno = 0;
    const size_t got = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    end_ += got;
    if (got > 0) continue;
    if (std::ferror(file_) && errno == EINTR) {
      std::clearerr(file_);
      continue;
    }
    eof_ = true;
    if (std::ferror(file_)) errno_ = errno ? errno : EIO;
  }
  // The file's true end, should it differ from the size it had when opened (or be unknown).
  if (eof_ || base_ + end_ > size_) size_ = base_ + end_;
  data_ = std::string_view(buffer_.data(), end_);
  if (progress_ && size_ && size_known()) progress_(double(base_ + end_) / double(size_));
  return view();
}

uint64_t ByteSource::learn_size() {
  while (!size_known()) {
    skip(end_ - pos_);
    fill(window_);
  }
  return size_;
}

bool ByteSource::make_seekable(std::string& error) {
  if (size_known()) return true;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> copy(std::tmpfile(), &std::fclose);
  auto fail = [&](int err) {
    error = std::string("cannot buffer the input: ") + std::strerror(err);
    return false;
  };
  if (!copy) return fail(errno);
  const uint64_t at = offset();
  uint64_t copied = 0;
  for (std::string_view w = peek(1); !w.empty(); w = peek(1)) {
    if (std::fwrite(w.data(), 1, w.size(), copy.get()) != w.size()) return fail(errno);
    copied += w.size();
    skip(w.size());
  }
  if (errno_) return false;
  if (std::fflush(copy.get()) != 0 || std::fseek(copy.get(), 0, SEEK_SET) != 0) return fail(errno);
  spilled_ = std::move(copy);
  file_ = spilled_.get();
  start_ = -long(at);
  base_ = at, pos_ = end_ = 0, eof_ = false;
  size_ = at + copied;
  data_ = std::string_view();
  return true;
}

std::string_view ByteSource::rest() {
  while (file_ && !eof_) fill(std::max<size_t>(end_ - pos_, window_ / 2) * 2);
  return view();
}

bool ByteSource::seek(uint64_t offset) {
  if (!file_) {
    pos_ = size_t(std::min<uint64_t>(offset, end_));
    return true;
  }
  if (offset >= base_ && offset <= base_ + end_) {
    pos_ = size_t(offset - base_);
    return true;
  }
  if (std::fseek(file_, start_ + long(offset), SEEK_SET) != 0) return false;
  base_ = offset, pos_ = end_ = 0, eof_ = false;
  data_ = std::string_view();
  return true;
}

std::string_view next_token(ByteSource& in) {
  std::string_view w = in.peek(1);
  size_t i = 0;
  for (;;) {  // spaces and line ends, across refills
    while (i < w.size() && is_space(w[i])) ++i;
    if (i < w.size() || w.empty()) break;
    in.skip(i), i = 0;
    w = in.peek(1);
  }
  in.skip(i);
  w = in.view();
  size_t j = 0;
  for (;;) {  // the token, the window grown until it holds it whole
    while (j < w.size() && !is_space(w[j])) ++j;
    if (j < w.size() || w.size() >= in.remaining()) break;
    const size_t searched = w.size();
    w = in.peek(searched * 2);
    if (w.size() == searched) break;  // a read failed
  }
  in.skip(j);
  return w.substr(0, j);
}

std::string line_error(const std::string& path, uint64_t line, const std::string& what) {
  return path + ": line " + std::to_string(line) + ": " + what;
}

std::string nonfinite_error(const std::string& path, uint64_t vertex, uint64_t line) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": vertex " + std::to_string(vertex) + where + " has a NaN or infinite coordinate";
}

std::string range_error(const std::string& path, uint64_t face, uint64_t line, int64_t index,
                        uint64_t vertices) {
  std::string where = line ? " (line " + std::to_string(line) + ")" : std::string();
  return path + ": face " + std::to_string(face) + where + " references vertex " +
         std::to_string(index) + ", but the file has " + std::to_string(vertices) +
         " vertices (0-based)";
}

void weld_vertices(PolygonSoup& soup) {
  std::unordered_map<uint64_t, std::vector<uint32_t>> buckets;
  std::vector<uint32_t> map(soup.vertex_count());
  std::vector<float> kept;
  kept.reserve(soup.positions.size());
  for (uint32_t v = 0; v < soup.vertex_count(); ++v) {
    float p[3];
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; ++k) {
      p[k] = soup.positions[size_t(v) * 3 + k];
      if (p[k] == 0) p[k] = 0;  // -0 -> +0
      h = (h ^ std::bit_cast<uint32_t>(p[k])) * 1099511628211ull;
    }
    std::vector<uint32_t>& bucket = buckets[h];
    map[v] = kNoAttribute;
    for (uint32_t w : bucket)
      if (std::memcmp(&kept[size_t(w) * 3], p, sizeof p) == 0) map[v] = w;
    if (map[v] == kNoAttribute) {
      map[v] = uint32_t(kept.size() / 3);
      bucket.push_back(map[v]);
      kept.insert(kept.end(), p, p + 3);
    }
  }
  soup.welded_vertices += soup.vertex_count() - kept.size() / 3;
  soup.positions = std::move(kept);
  for (uint32_t& c : soup.corners) c = map[c];
}

}  // namespace pmz
