// Private: the bake's output file and the end of a world file (world_format.h), shared by the
// bake's stages (world_writer.cpp) and the writing of its index, TIFF directories and locator
// (world_file_end.cpp).
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "format.h"
#include "io/durable_file.h"
#include "io/world_format.h"
#include "ridgeline/world.h"
#include "world/page.h"

namespace ridgeline::io::world_file {

// The output file: a temporary beside the target, removed unless committed.
class Output {
 public:
  explicit Output(std::string path) : path_(std::move(path)) {
    tmp_ = path_ + ".tmp." + std::to_string(::getpid());
  }
  ~Output() {
    if (fd_ >= 0) ::close(fd_);
    if (!committed_) ::unlink(tmp_.c_str());
  }
  Status open() {
    fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_ < 0)
      return Error{detail::fmt("bake '%s': cannot create '%s' (%s)", path_.c_str(), tmp_.c_str(),
                       std::strerror(errno))};
    return {};
  }
  std::uint64_t size() const noexcept { return at_; }
  Status write(const void* data, std::size_t n) { return pwrite(at_, data, n, true); }
  Status pwrite(std::uint64_t offset, const void* data, std::size_t n, bool advance = false) {
    const auto* p = static_cast<const std::uint8_t*>(data);
    std::size_t done = 0;
    while (done < n) {
      const ssize_t w = ::pwrite(fd_, p + done, n - done, off_t(offset + done));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        const int err = w < 0 ? errno : ENOSPC;
        return Error{detail::fmt("bake '%s': writing failed (%s); nothing was written to '%s'",
                         path_.c_str(), std::strerror(err), path_.c_str())};
      }
      done += std::size_t(w);
    }
    if (advance) at_ = std::max(at_, offset + n);
    return {};
  }
  Status commit() {
    // Closed here; flushed, renamed and the folder flushed by io/durable_file.h.
    const int err = ::close(fd_) != 0 ? errno : 0;
    fd_ = -1;
    Status s = err != 0 ? Status{Error{detail::fmt("flushing failed (%s)", std::strerror(err))}}
                        : durable::put_in_place(tmp_, path_);
    if (!s)
      return Error{detail::fmt("bake '%s': %s; nothing was written to '%s'", path_.c_str(),
                       s.message().c_str(), path_.c_str())};
    committed_ = true;
    return {};
  }

 private:
  std::string path_, tmp_;
  int fd_ = -1;
  std::uint64_t at_ = 0;
  bool committed_ = false;
};

/// TIFF-only tiles past a level's last page, by page index: (offset, bytes).
using EdgeTiles = std::unordered_map<std::size_t, std::pair<std::uint64_t, std::uint64_t>>;

/// What the end of a world file is made from, once every page is written.
struct FileEnd {
  const WorldInfo& info;
  bool store_u16, materials;
  std::uint32_t patch_exponent;
  double morph_window, morph_delay;
  const world::PageGrid& grid;
  const std::vector<std::size_t>& level_first;  // index of each level's first page
  const std::vector<PageSummary>& summaries;
  const std::vector<PageEntry>& entries;
  const std::vector<HoleRun>& hole_runs;
  const EdgeTiles &edge_x, &edge_z, &edge_xz;
};

/// Writes the chunks of page entries, the index, the TIFF directories of the heights and their
/// overviews, then the BigTIFF header and the locator at the start of the file.
Status write_file_end(Output& out, const FileEnd& end);

}  // namespace ridgeline::io::world_file
