// SPDX-License-Identifier: MIT
// What every pmz program (the command-line tools and pmz-view) does the same way: the
// exit-code convention, one-line errors ("pmz-encode: out.pmz: cannot write: No space left on
// device"), CLI11 set-up, `-` for stdin/stdout, safe output files (temporary + rename for regular
// files, removed on error and on SIGINT/SIGTERM/SIGHUP/SIGPIPE; symlinks keep pointing at their
// updated target; devices and FIFOs written directly: meshio's OutputFile) and a progress bar on
// stderr. Standard library, CLI11 and meshio only: the decoder's tools and the viewer use it too.
#pragma once
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <pmz/output_file.hpp>
#include <string>
#include <vector>

namespace pmz::app_support {

// The convention of every tool (stated in each --help and the README).
constexpr int kExitOk = 0;       // success
constexpr int kExitFailure = 1;  // the work failed: bad or damaged input, cannot read or write
constexpr int kExitUsage = 2;    // bad command line
extern const char* const kExitStatusHelp;

// Names the tool for messages and installs the SIGINT/SIGTERM/SIGHUP/SIGPIPE handler that removes
// the temporary files of outputs not yet committed, then dies of the same signal.
void init(const char* tool_name);
const char* name();

// "tool: text" on stderr, one line (after erasing a progress bar that is shown: no message
// lands on the bar's line).
void print_error(const std::string& text);
// "tool: file: text" on stderr, one line.
void print_error(const std::string& file, const std::string& text);

// A library message without its "pmz: " prefix (the tool's line names the tool and file).
std::string library_message(const std::string& message);

// Why a .pmz stream of `size` bytes was refused, for "tool: file: reason": "empty file" when it
// had no bytes at all, else the decoder's message without its "pmz: " prefix. Every tool that
// reads streams words its errors through this.
std::string stream_error(uint64_t size, const std::string& decoder_message);

// The project's version ("0.1.0"): every program's --version prints "NAME VERSION".
const char* version();

// Parses, with --version added; on --help or --version prints it and returns kExitOk (even
// without the required arguments), on a usage error prints "NAME: what (see --help)" (NAME: the
// app's name) and returns kExitUsage; returns -1 when the program should go on.
int parse(CLI::App& app, int argc, char** argv);
// A usage error found after parsing: prints "tool: what (see --help)", returns kExitUsage.
int usage_error(const std::string& what);
// The footer every tool's --help ends with (exit codes), after `extra` if any.
void set_footer(CLI::App& app, const std::string& extra = "");

// "path: reason" for errno (strerror).
std::string errno_message(const std::string& path, const char* action, int err);

// Opens a file for reading, stdin for "-" (not to be closed). error: "path: cannot read: reason"
// (a directory too).
FILE* open_input(const std::string& path, std::string& error);
// Reads a whole file, or stdin for "-". error: "path: cannot read: reason". `progress`, if set,
// is told the fraction of a regular file's size read so far.
bool read_input(const std::string& path, std::vector<uint8_t>& out, std::string& error,
                const std::function<void(double)>& progress = {});

// True when both name the same existing regular file (same device and inode, through links):
// writing the output would destroy the input. "-" is never the same file.
bool same_file(const std::string& a, const std::string& b);

// Lower-case extension without the dot ("" if none).
std::string extension(const std::string& path);

// The format a mesh output is written in, one rule for every program: the output's extension
// when it names a format meshio writes (pmz/mesh_file_formats.hpp), else `format` (the --format
// option) for an output without one (stdout "-", devices such as /dev/null, any other name).
// Returns "" with a usage message naming the accepted formats in `problem` when neither gives a
// format meshio writes.
std::string mesh_output_format(const std::string& output, const std::string& format,
                               std::string& problem);

// Safe output files and scratch files: meshio's one implementation (pmz/output_file.hpp), whose
// registered temporaries init()'s signal handler removes.
using pmz::OutputFile;
using pmz::ScratchFile;

// Writes `data` to `path` through an OutputFile.
bool write_output(const std::string& path, const void* data, size_t size, std::string& error);

// A progress bar on stderr: "\rpmz-encode: simplifying [=====>     ]  42%". Enabled when
// stderr is a terminal, unless quiet; `force` enables it anywhere (each bar then ends with a
// newline instead of being erased). print_error() erases a shown bar before its line; the bar is
// drawn again at its next update.
class Progress {
 public:
  Progress(bool quiet, bool force);
  ~Progress();
  bool enabled() const { return enabled_; }
  void update(const char* stage, double fraction);  // redraws when the percentage changes
  void clear();                                     // erases the bar (or ends its line)

 private:
  friend void print_error(const std::string& text);
  void clear_locked();  // with stderr's lock held
  bool enabled_ = false, tty_ = false, shown_ = false;
  int last_percent_ = -1;
  const char* last_stage_ = nullptr;
};

// The memory a process of this machine may use, in bytes: the smaller of its physical memory
// and the memory limit of its cgroup (v2 memory.max, v1 memory.limit_in_bytes) when one is set;
// 0 when neither can be read.
uint64_t machine_memory();

// A byte count as a user writes it: digits with an optional k, M, G or T (powers of 1024; "1.5G"
// allowed) and an optional B ("512MB"). False on anything else and on more than 2^62 bytes.
bool parse_byte_size(const std::string& text, uint64_t& bytes);
// Bytes as the tools print them: "812 MB", "4.73 GB" (powers of 1024, three significant figures).
std::string byte_size_text(uint64_t bytes);

// Adds --quiet and --progress to a tool.
void add_progress_options(CLI::App& app, bool& quiet, bool& force);

}  // namespace pmz::app_support
