// Edit files (edit_file.h): the core's edit file bytes (edit/edit_file.cpp) written durably
// (durable_file.h) and read back through C stdio.
#include "ridgeline/edit_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "io/durable_file.h"

namespace ridgeline::io {

Status save_edits(const Terrain& terrain, const std::string& path) {
  auto file = durable::File::create(path);
  if (!file) return Error{"save edits '" + path + "': " + file.error().message};
  struct Sink final : EditSink {
    explicit Sink(durable::File& f) : file(f) {}
    Status write(std::string_view bytes) override { return file.write(bytes); }
    durable::File& file;
  } sink(*file);
  Status s = ridgeline::save_edits(terrain, sink);
  if (s) s = file->commit();
  if (!s)
    return Error{"save edits '" + path + "': " + s.message() + "; the previous file is unchanged"};
  return {};
}

Result<EditResult> load_edits(Terrain& terrain, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Error{"load edits '" + path + "': " + std::strerror(errno)};
  struct Source final : EditSource {
    explicit Source(std::FILE* file) : f(file) {}
    Result<std::size_t> read(std::span<char> buffer) override {
      const std::size_t n = std::fread(buffer.data(), 1, buffer.size(), f);
      if (n == 0 && std::ferror(f))
        return Error{std::string("read error (") + std::strerror(errno) + ")"};
      return n;
    }
    std::FILE* f;
  } source(f);
  auto r = ridgeline::load_edits(terrain, source);
  std::fclose(f);
  if (!r) return Error{"load edits '" + path + "': " + r.error().message};
  return r;
}

}  // namespace ridgeline::io
