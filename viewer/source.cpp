// SPDX-License-Identifier: MIT
#include "source.hpp"

#include <curl/curl.h>
#include <fcntl.h>
#include <poll.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <list>
#include <thread>
#include <vector>

namespace pmzview {
namespace {

// A file or stdin. poll() with a timeout so a stop request is seen while a pipe is idle.
class FdSource final : public Source {
 public:
  FdSource(int fd, bool owned, uint64_t size) : fd_(fd), owned_(owned) { total_ = size; }
  ~FdSource() override {
    if (owned_) close(fd_);
  }

  std::string run(const ByteSink& sink, const std::atomic<bool>& stop) override {
    std::vector<uint8_t> buffer(64 * 1024);
    while (!stop.load()) {
      pollfd p{fd_, POLLIN, 0};
      int ready = poll(&p, 1, 100);
      if (ready < 0 && errno != EINTR) return std::string("cannot read: ") + std::strerror(errno);
      if (ready <= 0) continue;
      ssize_t n = read(fd_, buffer.data(), buffer.size());
      if (n < 0) {
        if (errno == EINTR || errno == EAGAIN) continue;
        return std::string("cannot read: ") + std::strerror(errno);
      }
      if (n == 0) break;
      if (!sink(buffer.data(), size_t(n))) break;
    }
    return "";
  }

  bool ranged() const override { return owned_ && total_ > 0; }

  std::string read_ranges(const std::vector<ByteRange>& ranges, const RangeSink& sink,
                          const ByteSink&, const std::atomic<bool>& stop) override {
    std::vector<uint8_t> buffer;
    for (size_t i = 0; i < ranges.size() && !stop.load(); ++i) {
      const uint64_t end = std::min(ranges[i].offset + ranges[i].size, total_.load());
      buffer.resize(end > ranges[i].offset ? size_t(end - ranges[i].offset) : 0);
      for (size_t got = 0; got < buffer.size();) {
        const ssize_t n =
            pread(fd_, buffer.data() + got, buffer.size() - got, off_t(ranges[i].offset + got));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) return std::string("cannot read: ") + std::strerror(errno);
        if (n == 0) return "cannot read: the file became shorter";
        got += size_t(n);
      }
      if (!sink(i, buffer.data(), buffer.size())) break;
    }
    return "";
  }

 private:
  int fd_;
  bool owned_;
};

class UrlSource final : public Source {
 public:
  explicit UrlSource(std::string url) : url_(std::move(url)) {}
  ~UrlSource() override {
    if (multi_) curl_multi_cleanup(multi_);
  }

  bool ranged() const override { return true; }
  std::string read_ranges(const std::vector<ByteRange>& ranges, const RangeSink& sink,
                          const ByteSink& in_order, const std::atomic<bool>& stop) override;

  std::string run(const ByteSink& sink, const std::atomic<bool>& stop) override {
    CURL* curl = curl_easy_init();
    if (!curl) return "cannot initialise libcurl";
    char error[CURL_ERROR_SIZE] = {};
    Context context{this, curl, &sink, &stop, false};
    curl_easy_setopt(curl, CURLOPT_URL, url_.c_str());
    curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, error);
    curl_easy_setopt(curl, CURLOPT_FAILONERROR, 1L);  // HTTP >= 400 is an error, not a body
    curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 1L);
    curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT, 15L);
    curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);  // we are on a worker thread
    curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, &UrlSource::on_write);
    curl_easy_setopt(curl, CURLOPT_WRITEDATA, &context);
    curl_easy_setopt(curl, CURLOPT_NOPROGRESS, 0L);
    curl_easy_setopt(curl, CURLOPT_XFERINFOFUNCTION, &UrlSource::on_progress);
    curl_easy_setopt(curl, CURLOPT_XFERINFODATA, &context);
    CURLcode code = curl_easy_perform(curl);
    curl_easy_cleanup(curl);
    if (code == CURLE_OK || context.stopped || stop.load()) return "";
    return std::string("fetch failed: ") + (error[0] ? error : curl_easy_strerror(code));
  }

 private:
  struct Context {
    UrlSource* self;
    CURL* curl;
    const ByteSink* sink;
    const std::atomic<bool>* stop;
    bool stopped;  // the sink asked to stop: the resulting write error is not a failure
  };

  static size_t on_write(char* data, size_t, size_t size, void* user) {
    auto* c = static_cast<Context*>(user);
    if (c->self->total_ == 0) {
      curl_off_t length = -1;
      if (curl_easy_getinfo(c->curl, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &length) == CURLE_OK &&
          length > 0)
        c->self->total_ = uint64_t(length);
    }
    if (c->stop->load() || !(*c->sink)(reinterpret_cast<const uint8_t*>(data), size)) {
      c->stopped = true;
      return 0;  // aborts the transfer
    }
    return size;
  }

  static int on_progress(void* user, curl_off_t, curl_off_t, curl_off_t, curl_off_t) {
    auto* c = static_cast<Context*>(user);
    if (c->stop->load()) {
      c->stopped = true;
      return 1;
    }
    return 0;
  }

  // One Range request in flight: its answer's status, Content-Range and body.
  struct Transfer {
    UrlSource* self = nullptr;
    CURL* curl = nullptr;
    size_t index = 0;
    ByteRange range;
    const ByteSink* in_order = nullptr;
    const std::atomic<bool>* stop = nullptr;
    long status = 0;  // 0 until the first byte of the body
    bool whole = false, stopped = false, too_long = false;
    std::string content_range;
    std::vector<uint8_t> body;
    char error[CURL_ERROR_SIZE] = {};
  };
  static size_t on_range_header(char* data, size_t, size_t size, void* user);
  static size_t on_range_write(char* data, size_t, size_t size, void* user);
  CURL* start_transfer(Transfer& t);
  std::string finish_transfer(Transfer& t, CURLcode code, const RangeSink& sink, bool& go_on);

  std::string url_;
  CURLM* multi_ = nullptr;  // kept across calls: its connections are reused
};

// Requests at once: enough to hide the round trips, few enough to be fair to a server.
constexpr size_t kRangesInFlight = 4;

size_t UrlSource::on_range_header(char* data, size_t, size_t size, void* user) {
  auto* t = static_cast<Transfer*>(user);
  constexpr char kName[] = "content-range:";
  if (size > sizeof kName - 1 && strncasecmp(data, kName, sizeof kName - 1) == 0) {
    size_t from = sizeof kName - 1;
    while (from < size && std::isspace(uint8_t(data[from]))) ++from;
    t->content_range.assign(data + from, size - from);
    while (!t->content_range.empty() && std::isspace(uint8_t(t->content_range.back())))
      t->content_range.pop_back();
  }
  return size;
}

size_t UrlSource::on_range_write(char* data, size_t, size_t size, void* user) {
  auto* t = static_cast<Transfer*>(user);
  if (t->status == 0) {
    curl_easy_getinfo(t->curl, CURLINFO_RESPONSE_CODE, &t->status);
    if (t->status == 200) {  // Range ignored: the whole body, read in order
      t->whole = true;
      t->self->ranges_ignored_ = true;
      curl_off_t length = -1;
      if (curl_easy_getinfo(t->curl, CURLINFO_CONTENT_LENGTH_DOWNLOAD_T, &length) == CURLE_OK &&
          length > 0)
        t->self->total_ = uint64_t(length);
    }
  }
  if (t->stop->load()) {
    t->stopped = true;
    return 0;
  }
  if (t->whole) {
    if (!(*t->in_order)(reinterpret_cast<const uint8_t*>(data), size)) {
      t->stopped = true;
      return 0;
    }
    return size;
  }
  if (t->body.size() + size > t->range.size) {
    t->too_long = true;
    return 0;
  }
  t->body.insert(t->body.end(), data, data + size);
  return size;
}

CURL* UrlSource::start_transfer(Transfer& t) {
  CURL* curl = curl_easy_init();
  if (!curl) return nullptr;
  t.curl = curl;
  const std::string range =
      std::to_string(t.range.offset) + "-" + std::to_string(t.range.offset + t.range.size - 1);
  curl_easy_setopt(curl, CURLOPT_URL, url_.c_str());
  curl_easy_setopt(curl, CURLOPT_RANGE, range.c_str());  // (copied by libcurl)
  curl_easy_setopt(curl, CURLOPT_ERRORBUFFER, t.error);
  curl_easy_setopt(curl, CURLOPT_FAILONERROR, 1L);
  curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 1L);
  curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT, 15L);
  // A server that stops sending is given up on instead of waited for.
  curl_easy_setopt(curl, CURLOPT_LOW_SPEED_LIMIT, 1L);
  curl_easy_setopt(curl, CURLOPT_LOW_SPEED_TIME, 30L);
  curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(curl, CURLOPT_HEADERFUNCTION, &UrlSource::on_range_header);
  curl_easy_setopt(curl, CURLOPT_HEADERDATA, &t);
  curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, &UrlSource::on_range_write);
  curl_easy_setopt(curl, CURLOPT_WRITEDATA, &t);
  return curl;
}

// Checks one finished transfer: a whole body (Range ignored) was read in order; a range must be
// answered by 206 with a Content-Range naming the bytes asked (cut at the end of the stream)
// and exactly that many bytes. go_on false: stop reading (the sink asked to, or an error).
std::string UrlSource::finish_transfer(Transfer& t, CURLcode code, const RangeSink& sink,
                                       bool& go_on) {
  go_on = false;
  const std::string asked = "bytes " + std::to_string(t.range.offset) + "-" +
                            std::to_string(t.range.offset + t.range.size - 1);
  if (t.stopped || t.stop->load()) return "";
  if (t.too_long) return asked + " asked: the server sent more than that";
  if (code != CURLE_OK)
    return asked + ": fetch failed: " + (t.error[0] ? t.error : curl_easy_strerror(code));
  if (t.whole) return "";  // the body went in order
  if (t.status == 0) curl_easy_getinfo(t.curl, CURLINFO_RESPONSE_CODE, &t.status);
  uint64_t first = 0, last = 0, total = 0;
  if (t.status != 206)
    return asked + ": the server answered HTTP " + std::to_string(t.status) + ", not 206";
  if (std::sscanf(t.content_range.c_str(), "bytes %" SCNu64 "-%" SCNu64 "/%" SCNu64, &first, &last,
                  &total) != 3 ||
      last < first || last >= total)
    return asked + ": the answer has no usable Content-Range ('" + t.content_range + "')";
  const uint64_t asked_last = t.range.offset + t.range.size - 1;
  if (first != t.range.offset || last > asked_last || (last < asked_last && last + 1 != total))
    return asked + " asked: the server answered " + t.content_range;
  if (t.body.size() != last - first + 1)
    return asked + " asked: " + std::to_string(t.body.size()) + " bytes answered for " +
           t.content_range;
  total_ = total;
  go_on = sink(t.index, t.body.data(), t.body.size());
  return "";
}

std::string UrlSource::read_ranges(const std::vector<ByteRange>& ranges, const RangeSink& sink,
                                   const ByteSink& in_order, const std::atomic<bool>& stop) {
  if (!multi_ && !(multi_ = curl_multi_init())) return "cannot initialise libcurl";
  std::list<Transfer> active;
  size_t next = 0;
  std::string error;
  bool go_on = true, whole = false;
  const auto remove = [&](std::list<Transfer>::iterator it) {
    curl_multi_remove_handle(multi_, it->curl);
    curl_easy_cleanup(it->curl);
    return active.erase(it);
  };
  while (error.empty() && go_on && !stop.load()) {
    while (!whole && next < ranges.size() && active.size() < kRangesInFlight) {
      Transfer& t = active.emplace_back();
      t.self = this;
      t.index = next;
      t.range = ranges[next++];
      t.in_order = &in_order;
      t.stop = &stop;
      if (!start_transfer(t)) {
        active.pop_back();
        return "cannot initialise libcurl";
      }
      curl_multi_add_handle(multi_, t.curl);
    }
    int running = 0;
    if (curl_multi_perform(multi_, &running) != CURLM_OK) {
      error = "fetch failed: libcurl's transfer loop failed";
      break;
    }
    int left = 0;
    while (CURLMsg* message = curl_multi_info_read(multi_, &left)) {
      if (message->msg != CURLMSG_DONE) continue;
      auto it = std::find_if(active.begin(), active.end(),
                             [&](const Transfer& t) { return t.curl == message->easy_handle; });
      if (it == active.end()) continue;
      const CURLcode code = message->data.result;
      bool more = false;
      const bool was_whole = it->whole;
      const std::string problem = finish_transfer(*it, code, sink, more);
      remove(it);
      if (!problem.empty()) error = problem;
      if (was_whole) return error;  // the whole body was read: nothing else is needed
      if (!more) go_on = false;
      if (!error.empty() || !go_on) break;
    }
    // A whole body coming in: the other ranges are within it, so they are dropped.
    if (!whole && ranges_ignored_.load()) {
      whole = true;
      for (auto it = active.begin(); it != active.end();)
        it = it->whole ? std::next(it) : remove(it);
    }
    if (active.empty() && next >= ranges.size()) break;
    curl_multi_poll(multi_, nullptr, 0, 100, nullptr);
  }
  while (!active.empty()) remove(active.begin());
  return error;
}

}  // namespace

std::string Source::read_ranges(const std::vector<ByteRange>&, const RangeSink&, const ByteSink&,
                                const std::atomic<bool>&) {
  return "cannot read by ranges";
}

bool is_url(const std::string& spec) {
  return spec.rfind("http://", 0) == 0 || spec.rfind("https://", 0) == 0;
}

std::unique_ptr<Source> open_source(const std::string& spec, std::string& error) {
  if (spec == "-") return std::make_unique<FdSource>(STDIN_FILENO, false, 0);
  if (is_url(spec)) return std::make_unique<UrlSource>(spec);
  int fd = open(spec.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    error = spec + ": cannot read: " + std::strerror(errno);
    return nullptr;
  }
  struct stat st {};
  if (fstat(fd, &st) != 0 || S_ISDIR(st.st_mode)) {
    error =
        spec + ": cannot read: " + (S_ISDIR(st.st_mode) ? "Is a directory" : std::strerror(errno));
    close(fd);
    return nullptr;
  }
  return std::make_unique<FdSource>(fd, true, S_ISREG(st.st_mode) ? uint64_t(st.st_size) : 0);
}

ByteSink throttled(ByteSink sink, double bytes_per_second, const std::atomic<bool>& stop) {
  if (bytes_per_second <= 0) return sink;
  using clock = std::chrono::steady_clock;
  struct State {
    clock::time_point start = clock::now();
    uint64_t passed = 0;
  };
  auto state = std::make_shared<State>();
  // Slices of ~1/30 s of data keep the arrival smooth rather than bursty.
  size_t slice = std::max<size_t>(256, size_t(bytes_per_second / 30));
  return [sink = std::move(sink), bytes_per_second, &stop, state, slice](const uint8_t* data,
                                                                         size_t size) {
    while (size > 0) {
      size_t n = std::min(slice, size);
      auto due = state->start +
                 std::chrono::duration_cast<clock::duration>(
                     std::chrono::duration<double>(double(state->passed + n) / bytes_per_second));
      while (clock::now() < due) {
        if (stop.load()) return false;
        std::this_thread::sleep_for(
            std::min<clock::duration>(due - clock::now(), std::chrono::milliseconds(50)));
      }
      if (!sink(data, n)) return false;
      state->passed += n;
      data += n;
      size -= n;
    }
    return true;
  };
}

}  // namespace pmzview
