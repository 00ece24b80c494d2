#include "analysis/io/file_io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace springscan::analysis {
namespace {

// Owns a file descriptor for the length of one call.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd() { close(); }
  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  /// Closes now and reports the result (close can report a deferred write error).
  int close() {
    if (fd_ < 0) return 0;
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc;
  }

 private:
  int fd_;
};

// The OS reason for the call that just failed; read at once, never later (STYLE.md section 5).
Error os_error(const std::string& what, const std::string& path) {
  const ErrorCode code = errno == ENOENT ? ErrorCode::kNotFound : ErrorCode::kIoError;
  return fail(code, what + " '" + path + "': " + std::strerror(errno));
}

}  // namespace

Expected<std::string> read_file_bytes(const std::string& path) {
  Fd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd.valid()) return os_error("cannot open", path);
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) return os_error("cannot stat", path);
  if (S_ISDIR(st.st_mode))
    return fail(ErrorCode::kIoError, "cannot read '" + path + "': it is a directory");
  // The size comes from the file system, not from file content, so it is safe to reserve.
  std::string bytes;
  bytes.resize(static_cast<std::size_t>(st.st_size));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return os_error("cannot read", path);
    if (n == 0) break;  // the file shrank while we read it
    done += static_cast<std::size_t>(n);
  }
  bytes.resize(done);
  return bytes;
}

Expected<bool> write_file_atomically(const std::string& path, std::string_view bytes) {
  const std::filesystem::path target(path);
  std::filesystem::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  // A unique temporary name (".name.XXXXXX"), so two writers of the same file (the CLI and the
  // daemon filling one model cache) never write into each other's temporary.
  // Built by append: `"." + name + ".tmp"` trips a g++ 12 -Wrestrict false positive.
  std::string tmp_name(1, '.');
  tmp_name.append(target.filename().string()).append(".XXXXXX");
  std::string tmp = (dir / tmp_name).string();
  Fd fd(::mkostemp(tmp.data(), O_CLOEXEC));
  if (!fd.valid()) return os_error("cannot create", tmp);
  // mkostemp makes the file 0600; reports and caches are read by the springscan group too.
  if (::fchmod(fd.get(), 0644) != 0) {
    Error error = os_error("cannot chmod", tmp);
    ::unlink(tmp.c_str());
    return error;
  }
  const auto abandon = [&](const std::string& what) {
    Error error = os_error(what, tmp);
    fd.close();
    ::unlink(tmp.c_str());
    return error;
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return abandon("cannot write");
    done += static_cast<std::size_t>(n);
  }
  // fsync before rename: otherwise a crash can leave the new name pointing at empty blocks.
  if (::fsync(fd.get()) != 0) return abandon("cannot fsync");
  if (fd.close() != 0) {
    Error error = os_error("cannot close", tmp);
    ::unlink(tmp.c_str());
    return error;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    Error error = os_error("cannot rename " + tmp + " to", path);
    ::unlink(tmp.c_str());
    return error;
  }
  // fsync the directory so that the rename itself survives a power loss.
  Fd dir_fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (!dir_fd.valid()) return os_error("cannot open directory", dir.string());
  if (::fsync(dir_fd.get()) != 0) return os_error("cannot fsync directory", dir.string());
  return true;
}

}  // namespace springscan::analysis
