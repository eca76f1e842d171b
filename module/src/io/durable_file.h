// Private to Ridgeline::io: files written so that a crash, a kill or a full disk never leaves a
// half-written file in place of the previous one (STYLE.md, "Errors: what bad input gets"): the
// data go to a temporary name beside the target, are flushed to disk, and the temporary file is
// renamed over the target, whose folder is flushed in turn.
//
// Two builds, chosen by the CMake option RIDGELINE_PORTABLE:
// - default (POSIX): open / write / fsync / rename / fsync of the folder (O_DIRECTORY), so the
//   new file survives a power cut once commit() returned;
// - RIDGELINE_PORTABLE: std::ofstream and std::filesystem::rename only. The rename still never
//   shows a half-written file after a crash of the process, but nothing is forced to disk: a
//   power cut may lose the new file (or, on some file systems, leave it empty).
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "ridgeline/result.h"

namespace ridgeline::io::durable {

/// The temporary name a durable write of `path` uses: in the same folder (so that the rename
/// stays within one file system), `path` + ".tmp." + an id of this process (its pid; in the
/// portable build a random number drawn once per process). Two processes saving the same path
/// never share a temporary file; two threads of one process must not save the same path at once.
std::string temp_path_of(const std::string& path);

/// A file written under temp_path_of(path) and put in place of `path` by commit(). Until
/// commit() succeeds, `path` is untouched; the destructor removes the temporary file of a write
/// that did not commit. Errors carry no path (the caller names what it saves): "cannot create
/// 'TMP': reason", "writing failed (reason)", "flushing failed (reason)", "rename failed
/// (reason)". Move-only; one thread at a time.
class File {
 public:
  /// Creates (or truncates) the temporary file.
  static Result<File> create(const std::string& path);
  File(File&& other) noexcept;
  File& operator=(File&&) = delete;
  File(const File&) = delete;
  ~File();

  /// Appends `bytes`.
  Status write(std::string_view bytes);
  /// Flushes the file to disk (POSIX: fsync; portable: the stream's own flush), closes it, renames
  /// it over `path` and flushes the folder (POSIX). On an error the temporary file is removed and
  /// `path` keeps what it held. Call once, after the last write().
  Status commit();

  const std::string& path() const noexcept { return path_; }
  const std::string& temp_path() const noexcept { return tmp_; }

 private:
  struct Handle;  // the open file: a descriptor, or a std::ofstream in the portable build
  File(std::string path, std::string tmp, std::unique_ptr<Handle> handle) noexcept;
  void discard() noexcept;  // closes and removes the temporary file

  std::string path_, tmp_;
  std::unique_ptr<Handle> handle_;  // null once committed or discarded
};

/// Puts a temporary file that is completely written and closed in place of `path`: flushes it to
/// disk, renames it over `path` and flushes the folder (portable build: the rename only). For
/// writers that keep their own descriptor (the world bake writes pages in parallel with pwrite).
/// POSIX: the file is opened again to be flushed; fsync flushes the file, whichever descriptor
/// names it, and reports a write-back error no descriptor has seen yet (Linux 4.16 and later).
/// On an error `tmp` is left for the caller to remove and `path` is untouched. Errors: "flushing
/// failed (reason)", "rename failed (reason)".
Status put_in_place(const std::string& tmp, const std::string& path);

}  // namespace ridgeline::io::durable
