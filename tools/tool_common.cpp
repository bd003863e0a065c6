#include "tool_common.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>

namespace pmz::tool {

const char* const kExitStatusHelp =
    "Exit status: 0 success, 1 failure (bad or damaged input, cannot read or write), 2 usage "
    "error.";

namespace {

const char* g_name = "pmz";
mode_t g_umask = 022;

// Temporaries of outputs not yet committed, for the signal handler: it may only use lock-free
// atomics and async-signal-safe calls (unlink, signal, raise). A slot's path is written before
// it is marked live and the slot is released only after the rename or removal, so the handler
// at worst unlinks a name that no longer exists. A batch of several workers has several slots.
constexpr int kTempSlots = 64;
struct TempSlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled or released, 2 live
  char path[PATH_MAX];
};
TempSlot g_temps[kTempSlots];

extern "C" void remove_temporaries_and_die(int sig) {
  for (TempSlot& slot : g_temps)
    if (slot.state.load() == 2) ::unlink(slot.path);
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}

int claim_temp_slot(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kTempSlots; ++i) {
    int expected = 0;
    if (g_temps[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_temps[i].path, path.c_str(), path.size() + 1);
      g_temps[i].state.store(2);
      return i;
    }
  }
  return -1;
}

void release_temp_slot(int slot) {
  if (slot < 0) return;
  g_temps[slot].state.store(1);
  g_temps[slot].path[0] = 0;
  g_temps[slot].state.store(0);
}

}  // namespace

void init(const char* tool_name) {
  g_name = tool_name;
  g_umask = ::umask(0);
  ::umask(g_umask);
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
  std::fprintf(stderr, "%s: %s\n", g_name, text.c_str());
}

void print_error(const std::string& file, const std::string& text) {
  std::fprintf(stderr, "%s: %s: %s\n", g_name, file.c_str(), text.c_str());
}

std::string library_message(const std::string& message) {
  return message.rfind("pmz: ", 0) == 0 ? message.substr(5) : message;
}

int parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::CallForAllHelp& e) {
    app.exit(e);
    return kExitOk;
  } catch (const CLI::ParseError& e) {
    return usage_error(e.what());
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

bool read_input(const std::string& path, std::vector<uint8_t>& out, std::string& error) {
  const bool from_stdin = path == "-";
  const std::string shown = from_stdin ? "stdin" : path;
  FILE* f = from_stdin ? stdin : std::fopen(path.c_str(), "rb");
  if (!f) return error = errno_message(shown, "cannot read", errno), false;
  struct stat st;
  if (::fstat(::fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
    if (!from_stdin) std::fclose(f);
    return error = shown + ": cannot read: Is a directory", false;
  }
  out.clear();
  uint8_t buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) out.insert(out.end(), buf, buf + n);
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

std::string extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  if (!e.empty()) e.erase(0, 1);
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

OutputFile::~OutputFile() { discard(); }

bool OutputFile::open(const std::string& path, bool binary, std::string& error) {
  discard();
  path_ = path;
  write_errno_ = 0;
  if (path == "-") {
    if (binary && ::isatty(1))
      return error = "stdout is a terminal: not writing binary data there (redirect it)", false;
    file_ = stdout;
    is_stdout_ = true;
    return true;
  }
  is_stdout_ = false;
  // Follow symlinks to the file they name (relative targets resolve against the link's
  // folder), so the rename below updates that file and the links stay.
  std::filesystem::path target(path);
  std::error_code ec;
  for (int hops = 0; hops < 40 && std::filesystem::is_symlink(target, ec); ++hops) {
    std::filesystem::path next = std::filesystem::read_symlink(target, ec);
    if (ec) break;
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  target_ = target.string();
  struct stat st;
  mode_t mode = 0666 & ~g_umask;
  if (::stat(target_.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return error = path + ": cannot write: Is a directory", false;
    if (!S_ISREG(st.st_mode)) {
      // A device, FIFO or socket: replacing the node by a regular file would destroy it.
      int fd = ::open(target_.c_str(), O_WRONLY | O_NOCTTY);
      if (fd < 0 || !(file_ = ::fdopen(fd, "wb"))) {
        const int err = errno;
        if (fd >= 0) ::close(fd);
        return error = errno_message(path, "cannot write", err), false;
      }
      return true;
    }
    mode = st.st_mode & 07777;
  }
  // The temporary: hidden, beside the target (same filesystem: the rename is atomic).
  const std::filesystem::path dir = target.parent_path();
  std::string temp = (dir / ("." + target.filename().string() + ".tmp.XXXXXX")).string();
  temp_slot_ = claim_temp_slot(temp);
  char* name_buf = temp_slot_ >= 0 ? g_temps[temp_slot_].path : temp.data();
  const int fd = ::mkstemp(name_buf);
  if (fd < 0) {
    const int err = errno;
    release_temp_slot(temp_slot_);
    temp_slot_ = -1;
    return error = errno_message(path, "cannot write", err), false;
  }
  temp = name_buf;
  if (temp_slot_ < 0) temp_slot_ = claim_temp_slot(temp);  // path was too long to pre-register
  ::fchmod(fd, mode);
  file_ = ::fdopen(fd, "wb");
  if (!file_) {
    const int err = errno;
    ::close(fd);
    ::unlink(temp.c_str());
    release_temp_slot(temp_slot_);
    temp_slot_ = -1;
    return error = errno_message(path, "cannot write", err), false;
  }
  temp_ = temp;
  return true;
}

bool OutputFile::write(const void* data, size_t size) {
  if (!file_) return false;
  if (size && std::fwrite(data, 1, size, file_) != size && !write_errno_)
    write_errno_ = errno ? errno : EIO;
  return !write_errno_;
}

bool OutputFile::commit(std::string& error) {
  if (!file_) return error = path_ + ": cannot write: not open", false;
  int err = write_errno_;
  if (std::fflush(file_) != 0 && !err) err = errno ? errno : EIO;
  if (std::ferror(file_) && !err) err = EIO;
  if (is_stdout_) {
    file_ = nullptr;
    if (err) return error = errno_message("stdout", "cannot write", err), false;
    return true;
  }
  if (std::fclose(file_) != 0 && !err) err = errno ? errno : EIO;
  file_ = nullptr;
  if (!err && !temp_.empty() && std::rename(temp_.c_str(), target_.c_str()) != 0) err = errno;
  if (err) {
    discard();
    return error = errno_message(path_, "cannot write", err), false;
  }
  temp_.clear();
  release_temp_slot(temp_slot_);
  temp_slot_ = -1;
  return true;
}

void OutputFile::discard() {
  if (file_ && !is_stdout_) std::fclose(file_);
  file_ = nullptr;
  if (!temp_.empty()) ::unlink(temp_.c_str());
  temp_.clear();
  release_temp_slot(temp_slot_);
  temp_slot_ = -1;
}

ScratchFile::~ScratchFile() {
  if (!path_.empty()) ::unlink(path_.c_str());
  release_temp_slot(slot_);
}

bool ScratchFile::create(const std::vector<uint8_t>& data, const std::string& suffix,
                         std::string& error) {
  const char* env = std::getenv("TMPDIR");
  const std::string dir = env && *env ? env : "/tmp";
  const std::string name = dir + "/" + g_name + ".XXXXXX" + suffix;
  auto fail = [&](int err) {
    return error = errno_message(dir, "cannot make a temporary file", err), false;
  };
  slot_ = claim_temp_slot(name);
  if (slot_ < 0) return fail(ENAMETOOLONG);
  const int fd = ::mkstemps(g_temps[slot_].path, int(suffix.size()));
  if (fd < 0) {
    const int err = errno;
    release_temp_slot(slot_);
    slot_ = -1;
    return fail(err);
  }
  path_ = g_temps[slot_].path;
  for (size_t done = 0; done < data.size();) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      return fail(err);
    }
    done += size_t(n);
  }
  if (::close(fd) != 0) return fail(errno);
  return true;
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

void Progress::update(const char* stage, double fraction) {
  if (!enabled_) return;
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
}

void Progress::clear() {
  if (!shown_) return;
  std::fputs(tty_ ? "\r\033[K" : "\n", stderr);
  shown_ = false;
  last_percent_ = -1;
  last_stage_ = nullptr;
}

void add_progress_options(CLI::App& app, bool& quiet, bool& force) {
  auto* q = app.add_flag("-q,--quiet", quiet, "no progress bar");
  auto* p =
      app.add_flag("--progress", force, "show the progress bar even when stderr is not a terminal");
  q->excludes(p);
}

}  // namespace pmz::tool
