// Durable writes (durable_file.h): temporary file, flush, rename, flush of the folder; POSIX
// calls by default, std::ofstream and std::filesystem with RIDGELINE_PORTABLE.
#include "io/durable_file.h"

#include <cerrno>
#include <cstring>
#include <system_error>

#ifdef RIDGELINE_PORTABLE
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>
#else
#include <fcntl.h>
#include <unistd.h>
#endif

#include "format.h"
#include "ridgeline/log.h"

namespace ridgeline::io::durable {

using ridgeline::detail::fmt;

#ifdef RIDGELINE_PORTABLE

struct File::Handle {
  std::ofstream out;
};

namespace {

// errno's text, or a plain word when the failing call left errno at 0: iostreams need not set it
// (libstdc++ does, through the write that failed).
std::string reason(int err) { return err != 0 ? std::strerror(err) : "unknown error"; }

}  // namespace

std::string temp_path_of(const std::string& path) {
  // No process id in standard C++: a random number drawn once per process takes its place.
  static const std::string id = [] {
    std::random_device rd;
    const std::uint64_t v = (std::uint64_t{rd()} << 32) ^ rd();
    return fmt("%016llx", static_cast<unsigned long long>(v));
  }();
  return path + ".tmp." + id;
}

Result<File> File::create(const std::string& path) {
  std::string tmp = temp_path_of(path);
  auto h = std::make_unique<Handle>();
  errno = 0;
  h->out.open(tmp, std::ios::binary | std::ios::trunc);
  if (!h->out.is_open()) return Error{fmt("cannot create '%s': %s", tmp.c_str(), reason(errno).c_str())};
  return File(path, std::move(tmp), std::move(h));
}

Status File::write(std::string_view bytes) {
  RIDGELINE_ASSERT(handle_);
  errno = 0;
  handle_->out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!handle_->out) {
    const int err = errno;
    discard();
    return Error{fmt("writing failed (%s)", reason(err).c_str())};
  }
  return {};
}

Status File::commit() {
  RIDGELINE_ASSERT(handle_);
  errno = 0;
  handle_->out.flush();
  handle_->out.close();
  if (handle_->out.fail()) {
    const int err = errno;
    discard();
    return Error{fmt("flushing failed (%s)", reason(err).c_str())};
  }
  if (Status s = put_in_place(tmp_, path_); !s) {
    discard();
    return s;
  }
  handle_.reset();
  return {};
}

void File::discard() noexcept {
  if (!handle_) return;
  if (handle_->out.is_open()) handle_->out.close();
  std::error_code ec;
  std::filesystem::remove(tmp_, ec);
  handle_.reset();
}

Status put_in_place(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) return Error{fmt("rename failed (%s)", ec.message().c_str())};
  return {};
}

#else  // POSIX

struct File::Handle {
  int fd = -1;
};

namespace {

// fsync, then close whatever fsync answered (a full disk may show only here: delayed
// allocation, network file systems). 0 or the first errno.
int flush_and_close(int fd) {
  int err = ::fsync(fd) != 0 ? errno : 0;
  if (::close(fd) != 0 && err == 0) err = errno;
  return err;
}

// Renames `tmp` over `path`, then flushes the folder so that the new name survives a power cut.
// The folder's flush is best effort: the data are saved by then, and a folder that cannot be
// opened (no read permission) must not turn a completed save into an error.
Status rename_over(const std::string& tmp, const std::string& path) {
  if (::rename(tmp.c_str(), path.c_str()) != 0)
    return Error{fmt("rename failed (%s)", std::strerror(errno))};
  const std::size_t slash = path.find_last_of('/');
  const std::string dir =
      slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return {};
}

}  // namespace

std::string temp_path_of(const std::string& path) {
  return path + ".tmp." + std::to_string(::getpid());
}

Result<File> File::create(const std::string& path) {
  std::string tmp = temp_path_of(path);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{fmt("cannot create '%s': %s", tmp.c_str(), std::strerror(errno))};
  auto h = std::make_unique<Handle>();
  h->fd = fd;
  return File(path, std::move(tmp), std::move(h));
}

Status File::write(std::string_view bytes) {
  RIDGELINE_ASSERT(handle_);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(handle_->fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      discard();
      return Error{fmt("writing failed (%s)", std::strerror(err))};
    }
    done += std::size_t(n);
  }
  return {};
}

Status File::commit() {
  RIDGELINE_ASSERT(handle_);
  const int err = flush_and_close(handle_->fd);
  handle_->fd = -1;
  if (err != 0) {
    discard();
    return Error{fmt("flushing failed (%s)", std::strerror(err))};
  }
  if (Status s = rename_over(tmp_, path_); !s) {
    discard();
    return s;
  }
  handle_.reset();
  return {};
}

void File::discard() noexcept {
  if (!handle_) return;
  if (handle_->fd >= 0) ::close(handle_->fd);
  ::unlink(tmp_.c_str());
  handle_.reset();
}

Status put_in_place(const std::string& tmp, const std::string& path) {
  const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Error{fmt("flushing failed (%s)", std::strerror(errno))};
  if (const int err = flush_and_close(fd); err != 0)
    return Error{fmt("flushing failed (%s)", std::strerror(err))};
  return rename_over(tmp, path);
}

#endif

File::File(std::string path, std::string tmp, std::unique_ptr<Handle> handle) noexcept
    : path_(std::move(path)), tmp_(std::move(tmp)), handle_(std::move(handle)) {}

File::File(File&& other) noexcept = default;

File::~File() { discard(); }

}  // namespace ridgeline::io::durable
