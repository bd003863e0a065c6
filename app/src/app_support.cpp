// SPDX-License-Identifier: MIT
#include "pmz/app_support.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <mutex>

#include "pmz/mesh_file_formats.hpp"

namespace pmz::app_support {

const char* const kExitStatusHelp =
    "Exit status: 0 success, 1 failure (bad or damaged input, cannot read or write), 2 usage "
    "error.";

namespace {

const char* g_name = "pmz";
// stderr's writers: messages and the bar shown on it (if any), which a message erases first.
std::mutex g_stderr;
Progress* g_shown_bar = nullptr;
extern "C" void remove_temporaries_and_die(int sig) {
  pmz::remove_output_temporaries();
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

}  // namespace

void init(const char* tool_name) {
  g_name = tool_name;
  pmz::init_output_files();
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction old = {};
    ::sigaction(sig, nullptr, &old);
    if (old.sa_handler == SIG_IGN) continue;  // e.g. nohup: stay ignored
    struct sigaction sa = {};
    sa.sa_handler = remove_temporaries_and_die;
    sigemptyset(&sa.sa_mask);
    ::sigaction(sig, &sa, nullptr);
  }
}

const char* name() { return g_name; }

void print_error(const std::string& text) {
  std::lock_guard<std::mutex> lock(g_stderr);
  if (g_shown_bar) g_shown_bar->clear_locked();
  std::fprintf(stderr, "%s: %s\n", g_name, text.c_str());
}

void print_error(const std::string& file, const std::string& text) {
  print_error(file + ": " + text);
}

std::string library_message(const std::string& message) {
  return message.rfind("pmz: ", 0) == 0 ? message.substr(5) : message;
}

const char* version() { return PMZ_APP_VERSION; }

std::string stream_error(uint64_t size, const std::string& decoder_message) {
  return size == 0 ? "empty file" : library_message(decoder_message);
}

int parse(CLI::App& app, int argc, char** argv) {
  app.set_version_flag("--version", app.get_name() + " " + version(),
                       "print the program's name and version, then exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForVersion& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::CallForHelp& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::CallForAllHelp& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: %s (see --help)\n", app.get_name().c_str(), e.what());
    return kExitUsage;
  }
  return -1;
}

int usage_error(const std::string& what) {
  print_error(what + " (see --help)");
  return kExitUsage;
}

void set_footer(CLI::App& app, const std::string& extra) {
  app.footer(extra.empty() ? kExitStatusHelp : extra + "\n\n" + kExitStatusHelp);
}

std::string errno_message(const std::string& path, const char* action, int err) {
  return path + ": " + action + ": " + std::strerror(err);
}

FILE* open_input(const std::string& path, std::string& error) {
  const bool from_stdin = path == "-";
  const std::string shown = from_stdin ? "stdin" : path;
  FILE* f = from_stdin ? stdin : std::fopen(path.c_str(), "rb");
  if (!f) return error = errno_message(shown, "cannot read", errno), nullptr;
  struct stat st = {};
  if (::fstat(::fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
    if (!from_stdin) std::fclose(f);
    return error = shown + ": cannot read: Is a directory", nullptr;
  }
  return f;
}

bool read_input(const std::string& path, std::vector<uint8_t>& out, std::string& error,
                const std::function<void(double)>& progress) {
  const bool from_stdin = path == "-";
  const std::string shown = from_stdin ? "stdin" : path;
  FILE* f = open_input(path, error);
  if (!f) return false;
  struct stat st = {};
  ::fstat(::fileno(f), &st);
  out.clear();
  const uint64_t size = S_ISREG(st.st_mode) ? uint64_t(st.st_size) : 0;
  if (size) out.reserve(size);
  uint8_t buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    out.insert(out.end(), buf, buf + n);
    if (progress && size) progress(double(out.size()) / double(size));
  }
  const int err = std::ferror(f) ? (errno ? errno : EIO) : 0;
  if (!from_stdin) std::fclose(f);
  if (err) return error = errno_message(shown, "cannot read", err), false;
  return true;
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  if (a == "-" || b == "-" || ::stat(a.c_str(), &sa) != 0 || ::stat(b.c_str(), &sb) != 0)
    return false;
  return S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

uint64_t machine_memory() {
  uint64_t bytes = 0;
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (pages > 0 && page > 0) bytes = uint64_t(pages) * uint64_t(page);
  // A container's limit: "max" (or a huge number under cgroup v1) means none.
  for (const char* path :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    FILE* f = std::fopen(path, "r");
    if (!f) continue;
    unsigned long long limit = 0;
    const bool number = std::fscanf(f, "%llu", &limit) == 1;
    std::fclose(f);
    if (number && limit > 0 && (bytes == 0 || limit < bytes)) bytes = limit;
  }
  return bytes;
}

bool parse_byte_size(const std::string& text, uint64_t& bytes) {
  size_t i = 0;
  double value = 0, scale = 1;
  bool digits = false, point = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c >= '0' && c <= '9') {
      digits = true;
      if (point) scale /= 10;
      value = value * 10 + (c - '0');
    } else if (c == '.' && !point) {
      point = true;
    } else {
      break;
    }
  }
  if (!digits) return false;
  value *= scale;
  static const char kUnits[] = "kmgt";
  if (i + 1 == text.size() && (text[i] == 'B' || text[i] == 'b') && !point) {
    ++i;  // plain bytes
  } else if (i < text.size()) {
    const char* unit = std::strchr(kUnits, std::tolower(static_cast<unsigned char>(text[i])));
    if (!unit || !*unit) return false;
    for (const char* u = kUnits; u <= unit; ++u) value *= 1024;
    ++i;
    if (i < text.size() && (text[i] == 'B' || text[i] == 'b')) ++i;
  } else if (point) {
    return false;  // (a fraction of a byte)
  }
  if (i != text.size() || value > double(uint64_t(1) << 62)) return false;
  bytes = uint64_t(value + 0.5);
  return true;
}

std::string byte_size_text(uint64_t bytes) {
  static const char* kUnits[] = {"bytes", "KB", "MB", "GB", "TB"};
  double value = double(bytes);
  int unit = 0;
  while (value >= 1024 && unit < 4) value /= 1024, ++unit;
  char buf[32];
  if (unit == 0)
    std::snprintf(buf, sizeof buf, "%llu bytes", (unsigned long long)bytes);
  else
    std::snprintf(buf, sizeof buf,
                  value < 10    ? "%.2f %s"
                  : value < 100 ? "%.1f %s"
                                : "%.0f %s",
                  value, kUnits[unit]);
  return buf;
}

std::string extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  if (!e.empty()) e.erase(0, 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

std::string mesh_output_format(const std::string& output, const std::string& format,
                               std::string& problem) {
  const std::string ext = output == "-" ? "" : extension(output);
  if (mesh_format_writable(ext)) return ext;
  if (mesh_format_writable(format)) return format;
  const std::string written = mesh_format_list(true, "|");
  if (!format.empty())
    problem = "--format " + format + " is read, not written: meshes are written as " + written;
  else if (output == "-")
    problem = "stdout (-) has no extension to name its format: give --format " + written;
  else if (ext.empty())
    problem = output + " has no extension to name its format: give --format " + written;
  else
    problem = output + ": no mesh format '." + ext + "' is written: name it " +
              mesh_format_list(true, ", ", " or ", ".") + ", or give --format " + written;
  return "";
}

bool write_output(const std::string& path, const void* data, size_t size, std::string& error) {
  OutputFile out;
  if (!out.open(path, true, error)) return false;
  out.write(data, size);
  return out.commit(error);
}

Progress::Progress(bool quiet, bool force) {
  tty_ = ::isatty(2);
  enabled_ = force || (!quiet && tty_);
}

Progress::~Progress() {
  std::lock_guard<std::mutex> lock(g_stderr);
  if (g_shown_bar == this) g_shown_bar = nullptr;
}

void Progress::update(const char* stage, double fraction) {
  if (!enabled_) return;
  std::lock_guard<std::mutex> lock(g_stderr);
  const int percent = int(std::min(1.0, std::max(0.0, fraction)) * 100);
  if (percent == last_percent_ && stage == last_stage_) return;
  last_percent_ = percent;
  last_stage_ = stage;
  constexpr int kWidth = 30;
  const int filled = percent * kWidth / 100;
  char bar[kWidth + 1];
  for (int i = 0; i < kWidth; ++i) bar[i] = i < filled ? '=' : i == filled ? '>' : ' ';
  bar[kWidth] = 0;
  std::fprintf(stderr, "\r%s: %s [%s] %3d%%", g_name, stage, bar, percent);
  std::fflush(stderr);
  shown_ = true;
  g_shown_bar = this;
}

void Progress::clear() {
  std::lock_guard<std::mutex> lock(g_stderr);
  clear_locked();
}

void Progress::clear_locked() {
  if (!shown_) return;
  std::fputs(tty_ ? "\r\033[K" : "\n", stderr);
  shown_ = false;
  last_percent_ = -1;
  last_stage_ = nullptr;
  if (g_shown_bar == this) g_shown_bar = nullptr;
}

void add_progress_options(CLI::App& app, bool& quiet, bool& force) {
  auto* q = app.add_flag("-q,--quiet", quiet, "no progress bar");
  auto* p =
      app.add_flag("--progress", force, "show the progress bar even when stderr is not a terminal");
  q->excludes(p);
}

}  // namespace pmz::app_support
