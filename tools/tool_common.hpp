// What every pmz command-line tool does the same way: the exit-code convention, one-line
// errors ("pmz-encode: out.pmz: cannot write: No space left on device"), CLI11 set-up, `-` for
// stdin/stdout, safe output files (temporary + rename for regular files, removed on error and on
// SIGINT/SIGTERM/SIGHUP/SIGPIPE; symlinks keep pointing at their updated target; devices and FIFOs
// written directly) and a progress bar on stderr. Standard library + CLI11 only: the decoder's
// tools use it too.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace pmz::tool {

// The convention of every tool (stated in each --help and the README).
constexpr int kExitOk = 0;       // success
constexpr int kExitFailure = 1;  // the work failed: bad or damaged input, cannot read or write
constexpr int kExitUsage = 2;    // bad command line
extern const char* const kExitStatusHelp;

// Names the tool for messages and installs the SIGINT/SIGTERM/SIGHUP/SIGPIPE handler that removes
// the temporary files of outputs not yet committed, then dies of the same signal.
void init(const char* tool_name);
const char* name();

// "tool: text" on stderr, one line.
void print_error(const std::string& text);
// "tool: file: text" on stderr, one line.
void print_error(const std::string& file, const std::string& text);

// A library message without its "pmz: " prefix (the tool's line names the tool and file).
std::string library_message(const std::string& message);

// Parses; on --help prints it and returns kExitOk, on a usage error prints "tool: what (see
// --help)" and returns kExitUsage; returns -1 when the tool should go on.
int parse(CLI::App& app, int argc, char** argv);
// A usage error found after parsing: prints "tool: what (see --help)", returns kExitUsage.
int usage_error(const std::string& what);
// The footer every tool's --help ends with (exit codes), after `extra` if any.
void set_footer(CLI::App& app, const std::string& extra = "");

// "path: reason" for errno (strerror).
std::string errno_message(const std::string& path, const char* action, int err);

// Reads a whole file, or stdin for "-". error: "path: cannot read: reason".
bool read_input(const std::string& path, std::vector<uint8_t>& out, std::string& error);

// True when both name the same existing regular file (same device and inode, through links):
// writing the output would destroy the input. "-" is never the same file.
bool same_file(const std::string& a, const std::string& b);

// Lower-case extension without the dot ("" if none).
std::string extension(const std::string& path);

// An output being written. open() decides how:
//   "-"                  stdout (refused when stdout is a terminal and the data is binary);
//   a device, FIFO, socket  written directly (a temporary + rename would replace the node);
//   a regular file or a new name  a hidden temporary beside the target (after following
//                        symlinks, so the link keeps pointing at the updated file), with the
//                        target's permissions, renamed over it by commit().
// Errors name the output as the user gave it, never the temporary.
class OutputFile {
 public:
  OutputFile() = default;
  ~OutputFile();  // discards what was not committed
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  bool open(const std::string& path, bool binary, std::string& error);
  FILE* stream() const { return file_; }
  // Buffered write; remembers the first failure's errno for commit().
  bool write(const void* data, size_t size);
  // Flushes and closes, renames the temporary into place. error: "path: cannot write: reason".
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

// A temporary file in $TMPDIR (else /tmp), for library calls that take a path (a mesh read
// from stdin, a mesh written for an output that is not a plain file); removed by the destructor
// and on SIGINT/SIGTERM/SIGHUP/SIGPIPE.
class ScratchFile {
 public:
  ScratchFile() = default;
  ~ScratchFile();
  ScratchFile(const ScratchFile&) = delete;
  ScratchFile& operator=(const ScratchFile&) = delete;
  // `suffix` e.g. ".obj" (readers and writers go by the extension); `data` its contents.
  bool create(const std::vector<uint8_t>& data, const std::string& suffix, std::string& error);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int slot_ = -1;
};

// Writes `data` to `path` through an OutputFile.
bool write_output(const std::string& path, const void* data, size_t size, std::string& error);

// A progress bar on stderr: "\rpmz-encode: simplifying [=====>     ]  42%". Enabled when
// stderr is a terminal, unless quiet; `force` enables it anywhere (each bar then ends with a
// newline instead of being erased).
class Progress {
 public:
  Progress(bool quiet, bool force);
  bool enabled() const { return enabled_; }
  void update(const char* stage, double fraction);  // redraws when the percentage changes
  void clear();                                     // erases the bar (or ends its line)

 private:
  bool enabled_ = false, tty_ = false, shown_ = false;
  int last_percent_ = -1;
  const char* last_stage_ = nullptr;
};

// Adds --quiet and --progress to a tool.
void add_progress_options(CLI::App& app, bool& quiet, bool& force);

}  // namespace pmz::tool
