// tridex command — output files written whole or not at all.
//
// Every output goes to a temporary file next to its destination and is renamed over it only once
// complete, so a failed or interrupted run leaves no partial or empty file and an existing file
// is replaced atomically (rename(2) within one directory). SIGINT, SIGTERM and SIGHUP remove the
// temporary files before the process dies (remove_temporaries_on_signals). An existing special
// file (a device node such as /dev/null, a FIFO) is written in place instead: renaming over it
// would replace the node with a regular file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace tridex::cli {

class AtomicOutput {
 public:
  // Opens a temporary file beside `path`; throws tridex::Error if it cannot be created.
  explicit AtomicOutput(std::filesystem::path path);
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();  // removes the temporary file unless commit() succeeded

  std::ostream& stream() { return stream_; }
  // Flushes, checks for write errors, closes and renames onto the destination.
  void commit();

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  std::filesystem::path temporary_;
  std::ofstream stream_;
  bool committed_ = false;
  bool in_place_ = false;  // a special file, written directly
  int slot_ = -1;          // in the signal handler's list of temporaries
};

// Writes `bytes` to `path` through an AtomicOutput.
void write_file_atomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);
void write_file_atomically(const std::filesystem::path& path, const std::string& text);

// Checks up front, before any work, that `path` can be written: its directory exists and is
// writable, it is not a directory, its name and its temporary file's name fit the file system's
// NAME_MAX (a temporary file is created there and removed again, so that any other refusal of the
// file system shows now rather than after the run), and it is none of `inputs`, compared by
// identity (device and inode: a run never overwrites an input, whatever path names it).
// Throws InputError naming `option` and the path.
void check_output_path(const std::string& option, const std::filesystem::path& path,
                       std::span<const std::filesystem::path> inputs);

// After the program is interpreted: throws InputError when an output names a file the run read
// that the up-front check could not know of (a subprogram found by O number or name while the
// program ran). Outputs are committed only after this, so such an input is never replaced.
void check_outputs_not_read(std::span<const std::pair<std::string, std::filesystem::path>> outputs,
                            std::span<const std::string> files_read);

// Throws InputError when two of (option, path) name the same file (special files excepted:
// they are written in place, and /dev/null may take several outputs).
void check_distinct_outputs(std::span<const std::pair<std::string, std::filesystem::path>> outputs);

// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove the temporary files of every
// AtomicOutput alive, then end the process by the same signal. Called once by main().
void remove_temporaries_on_signals();

}  // namespace tridex::cli
