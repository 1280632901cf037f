#include "outputs/output.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <mutex>
#include <system_error>

#include "errors.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

fs::path directory_of(const fs::path& path) {
  fs::path parent = path.parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

// An existing file that is neither regular nor a directory (a device node, a FIFO): written in
// place, never renamed over (that would replace /dev/null with a regular file).
bool is_special_file(const fs::path& path) {
  std::error_code error;
  fs::file_status status = fs::status(path, error);
  return !error && fs::exists(status) && !fs::is_regular_file(status) && !fs::is_directory(status);
}

// The temporary files alive now, for the signal handler: fixed storage, since a handler may not
// allocate. Slots are claimed under a mutex; a slot is shown to the handler (busy = true) only
// once its name is complete.
constexpr std::size_t kTemporarySlots = 64;
char temporary_names[kTemporarySlots][4096];
std::atomic<bool> temporary_busy[kTemporarySlots];
bool temporary_claimed[kTemporarySlots];
std::mutex temporary_mutex;

int register_temporary(const std::string& name) {
  if (name.size() >= sizeof temporary_names[0]) return -1;
  std::lock_guard lock(temporary_mutex);
  for (std::size_t k = 0; k < kTemporarySlots; ++k) {
    if (temporary_claimed[k]) continue;
    temporary_claimed[k] = true;
    std::memcpy(temporary_names[k], name.c_str(), name.size() + 1);
    temporary_busy[k].store(true);
    return static_cast<int>(k);
  }
  return -1;  // more than kTemporarySlots outputs at once: that one is not removed on a signal
}

void unregister_temporary(int slot) {
  if (slot < 0) return;
  std::lock_guard lock(temporary_mutex);
  temporary_busy[static_cast<std::size_t>(slot)].store(false);
  temporary_claimed[static_cast<std::size_t>(slot)] = false;
}

extern "C" void remove_temporaries_and_die(int signal_number) {
  for (std::size_t k = 0; k < kTemporarySlots; ++k)
    if (temporary_busy[k].load()) ::unlink(temporary_names[k]);
  // Die of the same signal, so the caller sees how the run ended.
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

}  // namespace

void remove_temporaries_on_signals() {
  for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal_number, &action, nullptr);
  }
}

AtomicOutput::AtomicOutput(fs::path path) : path_(std::move(path)) {
  if (is_special_file(path_)) {
    in_place_ = true;
    stream_.open(path_, std::ios::binary | std::ios::out);
    if (!stream_) detail::fail("cannot open ", path_.string(), " for writing");
    return;
  }
  // mkstemp gives a unique name that no concurrent run can collide with; the descriptor is only
  // used to reserve the name, the stream reopens it.
  // (Built by appending: GCC 12 warns falsely on `"." + string + "..."` under -Werror=restrict.)
  std::string name = ".";
  name.append(path_.filename().string()).append(".tmp-XXXXXX");
  std::string pattern = (directory_of(path_) / name).string();
  // No signal between creating the file and listing it for the handler.
  sigset_t cleanup_signals, previous;
  sigemptyset(&cleanup_signals);
  for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&cleanup_signals, signal_number);
  ::pthread_sigmask(SIG_BLOCK, &cleanup_signals, &previous);
  int fd = ::mkstemp(pattern.data());
  if (fd >= 0) slot_ = register_temporary(pattern);
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (fd < 0)
    detail::fail("cannot create a temporary file for ", path_.string(), ": ", std::strerror(errno));
  ::close(fd);
  temporary_ = pattern;
  stream_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!stream_) {
    std::error_code ignored;
    fs::remove(temporary_, ignored);
    unregister_temporary(slot_);
    detail::fail("cannot open ", temporary_.string(), " for writing");
  }
}

AtomicOutput::~AtomicOutput() {
  if (committed_) return;
  stream_.close();
  if (in_place_) return;
  std::error_code ignored;
  fs::remove(temporary_, ignored);
  unregister_temporary(slot_);
}

void AtomicOutput::commit() {
  stream_.flush();
  bool good = static_cast<bool>(stream_);
  stream_.close();
  if (!good || stream_.fail()) detail::fail("error while writing ", path_.string());
  if (in_place_) {
    committed_ = true;
    return;
  }
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
  unregister_temporary(slot_);
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

namespace {

// The same file as `input` (device and inode): a hard link or another spelling of its path counts.
bool same_file(const fs::path& path, const fs::path& input) {
  struct stat a {
  }, b{};
  if (::stat(path.c_str(), &a) != 0 || ::stat(input.c_str(), &b) != 0) return false;
  return a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

// The name and the temporary file's must fit the folder's NAME_MAX; then a temporary file is
// created and removed, as AtomicOutput will, so that the file system's refusal shows before the
// run.
void check_name_fits(const std::string& option, const fs::path& path, const fs::path& directory) {
  long name_max = ::pathconf(directory.c_str(), _PC_NAME_MAX);
  if (name_max <= 0) name_max = 255;
  const std::string name = path.filename().string();
  const std::size_t temporary_length = name.size() + std::string(".").size() + 11;  // .tmp-XXXXXX
  if (name.size() > static_cast<std::size_t>(name_max) ||
      temporary_length > static_cast<std::size_t>(name_max))
    input_error(option, " ", path.string(), ": the file name is ", name.size(),
                " bytes long, too long for this file system (", name_max, " bytes at most, ",
                temporary_length - name.size(),
                " fewer for the temporary file it is written through)");
  std::string pattern = (directory / ("." + name + ".tmp-XXXXXX")).string();
  sigset_t cleanup_signals, previous;
  sigemptyset(&cleanup_signals);
  for (int signal_number : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&cleanup_signals, signal_number);
  ::pthread_sigmask(SIG_BLOCK, &cleanup_signals, &previous);
  int fd = ::mkstemp(pattern.data());
  const int failure = errno;
  if (fd >= 0) {
    ::close(fd);
    ::unlink(pattern.c_str());
  }
  ::pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  if (fd < 0)
    input_error(option, " ", path.string(),
                ": cannot create a file there: ", std::strerror(failure));
}

}  // namespace

void check_output_path(const std::string& option, const fs::path& path,
                       std::span<const fs::path> inputs) {
  if (path.empty()) input_error(option, ": empty file name");
  std::error_code error;
  if (fs::is_directory(path, error)) input_error(option, " ", path.string(), ": is a directory");
  if (is_special_file(path)) {  // written in place
    if (::access(path.c_str(), W_OK) != 0)
      input_error(option, " ", path.string(), ": is not writable");
    return;
  }
  for (const fs::path& input : inputs)
    if (!input.empty() && same_file(path, input))
      input_error(option, " ", path.string(), ": would overwrite an input (", input.string(), ")");
  fs::path directory = directory_of(path);
  if (!fs::is_directory(directory, error))
    input_error(option, " ", path.string(), ": directory ", directory.string(), " does not exist");
  if (::access(directory.c_str(), W_OK | X_OK) != 0)
    input_error(option, " ", path.string(), ": directory ", directory.string(), " is not writable");
  check_name_fits(option, path, directory);
}

void check_outputs_not_read(std::span<const std::pair<std::string, fs::path>> outputs,
                            std::span<const std::string> files_read) {
  for (const auto& [option, path] : outputs) {
    if (path.empty() || path == "-" || is_special_file(path)) continue;
    for (const std::string& input : files_read)
      if (same_file(path, input))
        input_error(option, " ", path.string(), ": would overwrite an input (", input,
                    ", read while the program ran); nothing was written");
  }
}

}  // namespace tridex::cli

namespace tridex::cli {

void check_distinct_outputs(std::span<const std::pair<std::string, fs::path>> outputs) {
  auto same_output = [](const fs::path& a, const fs::path& b) {
    std::error_code error;
    if (fs::exists(a, error) && fs::exists(b, error)) return fs::equivalent(a, b, error);
    // Not written yet: compare the paths they will have (through any links in the directories).
    return fs::weakly_canonical(fs::absolute(a), error) ==
           fs::weakly_canonical(fs::absolute(b), error);
  };
  for (std::size_t i = 0; i < outputs.size(); ++i)
    for (std::size_t j = i + 1; j < outputs.size(); ++j) {
      const auto& [first_option, first] = outputs[i];
      const auto& [second_option, second] = outputs[j];
      if (first.empty() || second.empty() || is_special_file(first)) continue;
      if (same_output(first, second))
        input_error(first_option, " ", first.string(), " and ", second_option, " ", second.string(),
                    " name the same file: one output would replace the other");
    }
}

}  // namespace tridex::cli
