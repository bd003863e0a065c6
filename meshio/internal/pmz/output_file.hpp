// SPDX-License-Identifier: MIT
// Safe output files, the one implementation behind meshio's write_mesh and every tool's output:
// a hidden temporary beside the target renamed over it when complete (symlinks followed, so a
// link keeps pointing at its updated target; the target's permissions kept), devices, FIFOs and
// sockets written directly, "-" is stdout. Temporaries not yet committed are registered so that
// a signal handler can remove them (remove_output_temporaries). A temporary is named
// ".NAME.tmp.PID.XXXXXX" after the target and the writing process: one left by a process that no
// longer runs (SIGKILL cannot be caught) is removed when the same target is next opened.
// Internal to the build: not an installed header.
#pragma once
#include <cstdio>
#include <string>
#include <vector>

namespace pmz {

// Errors name the output as the caller gave it, never the temporary:
// "path: cannot write: reason".
class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();  // discards what was not committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // `binary`: "-" is refused when stdout is a terminal.
  bool open(const std::string& path, bool binary, std::string& error);
  FILE* stream() const { return file_; }
  // Buffered write; remembers the first failure's errno for commit().
  bool write(const void* data, size_t size);
  // Flushes and closes, renames the temporary into place.
  bool commit(std::string& error);
  // Closes and removes the temporary (a direct output is left as it is).
  void discard();
  const std::string& path() const { return path_; }

 private:
  std::string path_;    // as given
  std::string target_;  // where the temporary is renamed to (symlinks resolved)
  std::string temp_;    // the temporary, while open
  FILE* file_ = nullptr;
  int temp_slot_ = -1;  // registered temporary (removed on signals), or -1
  int write_errno_ = 0;
  bool is_stdout_ = false;
};

// A temporary file in $TMPDIR (else /tmp) named PREFIX.PID.XXXXXX+suffix, for library calls
// that take a path (a mesh read from stdin is parsed under its name); removed by the destructor and
// by remove_output_temporaries(), and one of a process that is gone (killed by SIGKILL) by the next
// create() with the same prefix and suffix.
class ScratchFile {
 public:
  ScratchFile() = default;
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
  // `suffix` e.g. ".obj" (readers and writers go by the extension); `data` its contents.
  bool create(const std::vector<uint8_t>& data, const std::string& prefix,
              const std::string& suffix, std::string& error);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int slot_ = -1;
};

// Unlinks every registered temporary. Async-signal-safe (lock-free atomics and unlink only):
// for a SIGINT/SIGTERM handler, which then re-raises the signal.
void remove_output_temporaries();

// Reads the process umask once (new files get 0666 & ~umask); call early in main() so that the
// read (umask is read by setting it) happens before other threads create files.
void init_output_files();

}  // namespace pmz
