// Bounded GDAL_NODATA reader (tiff_tags.h).
#include "io/tiff_tags.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

namespace ridgeline::io::detail {

namespace {

constexpr std::uint16_t kGdalNodataTag = 42113;
constexpr std::uint16_t kAscii = 2;

struct Reader {
  const ReadAt& read;
  std::uint64_t size;
  bool little;

  bool bytes(std::uint64_t offset, std::size_t n, unsigned char* out) const {
    if (offset > size || n > size - offset) return false;
    return read(offset, n, out);
  }
  std::uint64_t value(const unsigned char* p, int n) const {
    std::uint64_t v = 0;
    for (int k = 0; k < n; ++k) v |= std::uint64_t{p[little ? k : n - 1 - k]} << (8 * k);
    return v;
  }
};

}  // namespace

Result<std::optional<std::string>> read_gdal_nodata(const ReadAt& read, std::uint64_t size) {
  unsigned char head[16];
  if (size < 8 || !read(0, 8, head)) return std::optional<std::string>{};
  const bool little = head[0] == 'I' && head[1] == 'I';
  if (!little && !(head[0] == 'M' && head[1] == 'M')) return std::optional<std::string>{};
  Reader r{read, size, little};
  const std::uint64_t magic = r.value(head + 2, 2);
  if (magic != 42 && magic != 43) return std::optional<std::string>{};
  const bool big = magic == 43;
  std::uint64_t ifd = 0;
  if (big) {
    if (!r.bytes(0, 16, head)) return Error{"BigTIFF header is truncated"};
    if (r.value(head + 4, 2) != 8) return Error{"BigTIFF header has an offset size other than 8"};
    ifd = r.value(head + 8, 8);
  } else {
    ifd = r.value(head + 4, 4);
  }
  // Entry layout: tag (2), type (2), count (4 | 8), value or offset (4 | 8).
  const int count_size = big ? 8 : 4, entry_size = big ? 20 : 12, head_size = big ? 8 : 2;
  unsigned char nbuf[8];
  if (!r.bytes(ifd, std::size_t(head_size), nbuf))
    return Error{"first IFD offset " + std::to_string(ifd) + " lies outside the file"};
  const std::uint64_t entries = r.value(nbuf, head_size);
  if (entries > kMaxIfdEntries)
    return Error{"first IFD claims " + std::to_string(entries) + " entries (at most " +
                 std::to_string(kMaxIfdEntries) + " are read)"};
  unsigned char e[20];
  for (std::uint64_t k = 0; k < entries; ++k) {
    const std::uint64_t at = ifd + std::uint64_t(head_size) + k * std::uint64_t(entry_size);
    if (!r.bytes(at, std::size_t(entry_size), e))
      return Error{"IFD entry " + std::to_string(k) + " lies outside the file"};
    if (r.value(e, 2) != kGdalNodataTag) continue;
    if (r.value(e + 2, 2) != kAscii)
      return Error{"GDAL_NODATA tag has type " + std::to_string(r.value(e + 2, 2)) +
                   "; expected 2 (ASCII)"};
    const std::uint64_t count = r.value(e + 4, count_size);
    if (count == 0) return std::optional<std::string>{std::string{}};
    if (count > kMaxNodataChars)
      return Error{"GDAL_NODATA tag holds " + std::to_string(count) + " characters (at most " +
                   std::to_string(kMaxNodataChars) + ")"};
    std::vector<unsigned char> text(count);
    const unsigned char* inline_value = e + 4 + count_size;
    if (count <= std::uint64_t(count_size)) {
      std::copy(inline_value, inline_value + count, text.begin());
    } else {
      const std::uint64_t off = r.value(inline_value, count_size);
      if (!r.bytes(off, std::size_t(count), text.data()))
        return Error{"GDAL_NODATA tag's value (" + std::to_string(count) + " bytes at offset " +
                     std::to_string(off) + ") lies outside the file"};
    }
    std::string s;
    for (unsigned char c : text) {
      if (c == 0) break;
      s.push_back(static_cast<char>(c));
    }
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
    std::size_t b = 0;
    while (b < s.size() && (s[b] == ' ' || s[b] == '\t')) ++b;
    return std::optional<std::string>{s.substr(b)};
  }
  return std::optional<std::string>{};
}

Result<std::optional<std::string>> read_gdal_nodata_file(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!f) return std::optional<std::string>{};
  if (std::fseek(f.get(), 0, SEEK_END) != 0) return std::optional<std::string>{};
  const long end = std::ftell(f.get());
  if (end < 0) return std::optional<std::string>{};
  ReadAt read = [&](std::uint64_t offset, std::size_t n, unsigned char* out) {
    if (offset > std::uint64_t(end)) return false;
    if (std::fseek(f.get(), static_cast<long>(offset), SEEK_SET) != 0) return false;
    return std::fread(out, 1, n, f.get()) == n;
  };
  return read_gdal_nodata(read, std::uint64_t(end));
}

std::optional<double> parse_nodata_text(const std::string& text) {
  if (text.empty()) return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  if (errno == ERANGE && std::isinf(v)) return std::nullopt;  // beyond double range
  return v;
}

}  // namespace ridgeline::io::detail
