// SPDX-License-Identifier: MIT
#include "pmz/output_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace pmz {

namespace {

std::string cannot(const std::string& path, const char* action, int err) {
  return path + ": " + action + ": " + std::strerror(err);
}

// umask can only be read by setting it: once, before the first file is made.
mode_t process_umask() {
  static const mode_t mask = [] {
    const mode_t m = ::umask(0);
    ::umask(m);
    return m;
  }();
  return mask;
}

// Temporaries not yet committed, for a signal handler: it may only use lock-free atomics and
// async-signal-safe calls (unlink). A slot's path is written before it is marked live and the
// slot is released only after the rename or removal, so the handler at worst unlinks a name
// that no longer exists. A batch of several workers has several slots.
constexpr int kTempSlots = 64;
struct TempSlot {
  std::atomic<int> state{0};  // 0 free, 1 being filled or released, 2 live
  char path[PATH_MAX];
};
TempSlot g_temps[kTempSlots];

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

// Removes the temporaries in `dir` named `prefix` + PID + "." + 6 characters + `suffix` whose
// process is gone: a process killed by SIGKILL had no chance to remove its own. One whose PID is
// alive (or belongs to another user's process) is left: it may still be in use.
void remove_stale_temporaries(const std::filesystem::path& dir, const std::string& prefix,
                              const std::string& suffix = "") {
  std::error_code ec;
  std::filesystem::directory_iterator it(dir.empty() ? std::filesystem::path(".") : dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    const char* digits = name.c_str() + prefix.size();
    char* after = nullptr;
    const long pid =
        std::isdigit(static_cast<unsigned char>(*digits)) ? std::strtol(digits, &after, 10) : 0;
    if (pid <= 0 || pid > INT_MAX || pid == long(::getpid()) || *after != '.' ||
        std::strlen(after + 1) != 6 + suffix.size() || !name.ends_with(suffix))
      continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;
    struct stat st;
    if (::lstat(it->path().c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::unlink(it->path().c_str());
  }
}

}  // namespace

void remove_output_temporaries() {
  for (TempSlot& slot : g_temps)
    if (slot.state.load() == 2) ::unlink(slot.path);
}

void init_output_files() { process_umask(); }

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
  mode_t mode = 0666 & ~process_umask();
  if (::stat(target_.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) return error = path + ": cannot write: Is a directory", false;
    if (!S_ISREG(st.st_mode)) {
      // A device, FIFO or socket: replacing the node by a regular file would destroy it.
      int fd = ::open(target_.c_str(), O_WRONLY | O_NOCTTY);
      if (fd < 0 || !(file_ = ::fdopen(fd, "wb"))) {
        const int err = errno;
        if (fd >= 0) ::close(fd);
        return error = cannot(path, "cannot write", err), false;
      }
      return true;
    }
    mode = st.st_mode & 07777;
  }
  // The temporary: hidden, beside the target (same filesystem: the rename is atomic).
  const std::filesystem::path dir = target.parent_path();
  // Appended rather than "." + name: GCC 12 warns falsely (-Wrestrict) on literal + string&&.
  std::string temp_name = ".";
  temp_name += target.filename().string();
  temp_name += ".tmp.";
  remove_stale_temporaries(dir, temp_name);
  temp_name += std::to_string(::getpid());
  temp_name += ".XXXXXX";
  std::string temp = (dir / temp_name).string();
  temp_slot_ = claim_temp_slot(temp);
  char* name_buf = temp_slot_ >= 0 ? g_temps[temp_slot_].path : temp.data();
  const int fd = ::mkstemp(name_buf);
  if (fd < 0) {
    const int err = errno;
    release_temp_slot(temp_slot_);
    temp_slot_ = -1;
    return error = cannot(path, "cannot write", err), false;
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
    return error = cannot(path, "cannot write", err), false;
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
    if (err) return error = cannot("stdout", "cannot write", err), false;
    return true;
  }
  if (std::fclose(file_) != 0 && !err) err = errno ? errno : EIO;
  file_ = nullptr;
  if (!err && !temp_.empty() && std::rename(temp_.c_str(), target_.c_str()) != 0) err = errno;
  if (err) {
    discard();
    return error = cannot(path_, "cannot write", err), false;
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

bool ScratchFile::create(const std::vector<uint8_t>& data, const std::string& prefix,
                         const std::string& suffix, std::string& error) {
  const char* env = std::getenv("TMPDIR");
  const std::string dir = env && *env ? env : "/tmp";
  // The PID in the name lets a later run remove what a killed one left (as outputs do).
  remove_stale_temporaries(dir, prefix + ".", suffix);
  const std::string name =
      dir + "/" + prefix + "." + std::to_string(::getpid()) + ".XXXXXX" + suffix;
  auto fail = [&](int err) {
    return error = cannot(dir, "cannot make a temporary file", err), false;
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

}  // namespace pmz
