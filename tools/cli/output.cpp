#include "output.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>

#include "errors.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

fs::path directory_of(const fs::path& path) {
  fs::path parent = path.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

}  // namespace

AtomicOutput::AtomicOutput(fs::path path) : path_(std::move(path)) {
  // mkstemp gives a unique name that no concurrent run can collide with; the descriptor is only
  // used to reserve the name, the stream reopens it.
  // (Built by appending: GCC 12 warns falsely on `"." + string + "..."` under -Werror=restrict.)
  std::string name = ".";
  name.append(path_.filename().string()).append(".tmp-XXXXXX");
  std::string pattern = (directory_of(path_) / name).string();
  int fd = ::mkstemp(pattern.data());
  if (fd < 0)
    detail::fail("cannot create a temporary file for ", path_.string(), ": ", std::strerror(errno));
  ::close(fd);
  temporary_ = pattern;
  stream_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    std::error_code ignored;
    fs::remove(temporary_, ignored);
    detail::fail("cannot open ", temporary_.string(), " for writing");
  }
}

AtomicOutput::~AtomicOutput() {
  if (committed_) return;
  stream_.close();
  std::error_code ignored;
  fs::remove(temporary_, ignored);
}

void AtomicOutput::commit() {
  stream_.flush();
  bool good = static_cast<bool>(stream_);
  stream_.close();
  if (!good || stream_.fail()) detail::fail("error while writing ", path_.string());
  // Files from mkstemp are private (0600); give the result the usual permissions.
  std::error_code ignored;
  fs::permissions(temporary_,
                  fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                      fs::perms::others_read,
                  fs::perm_options::replace, ignored);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0)
    detail::fail("cannot rename ", temporary_.string(), " to ", path_.string(), ": ",
                 std::strerror(errno));
  committed_ = true;
}

void write_file_atomically(const fs::path& path, std::span<const std::uint8_t> bytes) {
  AtomicOutput out(path);
  out.stream().write(reinterpret_cast<const char*>(bytes.data()),
                     static_cast<std::streamsize>(bytes.size()));
  out.commit();
}

void write_file_atomically(const fs::path& path, const std::string& text) {
  AtomicOutput out(path);
  out.stream() << text;
  out.commit();
}

void check_output_path(const std::string& option, const fs::path& path,
                       std::span<const fs::path> inputs) {
  if (path.empty()) input_error(option, ": empty file name");
  std::error_code error;
  if (fs::is_directory(path, error)) input_error(option, " ", path.string(), ": is a directory");
  fs::path directory = directory_of(path);
  if (!fs::is_directory(directory, error))
    input_error(option, " ", path.string(), ": directory ", directory.string(), " does not exist");
  if (::access(directory.c_str(), W_OK | X_OK) != 0)
    input_error(option, " ", path.string(), ": directory ", directory.string(),
                " is not writable");
  if (fs::exists(path, error))
    for (const fs::path& input : inputs)
      if (fs::exists(input, error) && fs::equivalent(path, input, error))
        input_error(option, " ", path.string(), ": would overwrite the input ", input.string());
}

}  // namespace tridex::cli
