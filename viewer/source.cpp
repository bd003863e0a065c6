// SPDX-License-Identifier: MIT
#include "source.hpp"

#include <curl/curl.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
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

 private:
  int fd_;
  bool owned_;
};

class UrlSource final : public Source {
 public:
  explicit UrlSource(std::string url) : url_(std::move(url)) {}

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

  std::string url_;
};

}  // namespace

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
