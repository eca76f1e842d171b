// Bounded TIFF tag reader (tiff_tags.h).
#include "io/tiff_tags.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>

namespace ridgeline::io::detail {

namespace {

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

// Bytes per value of a TIFF field type; 0 for types this reader does not decode.
int type_size(std::uint64_t type) {
  switch (type) {
    case 1:
    case 2:
    case 6:
    case 7:
      return 1;  // BYTE, ASCII, SBYTE, UNDEFINED
    case 3:
    case 8:
      return 2;  // SHORT, SSHORT
    case 4:
    case 9:
    case 11:
      return 4;  // LONG, SLONG, FLOAT
    case 5:
    case 10:
    case 12:
    case 16:
    case 17:
      return 8;  // RATIONAL, SRATIONAL, DOUBLE, LONG8, SLONG8
    default:
      return 0;
  }
}

template <class S, class U>
double as_signed(U u) {
  S s;
  std::memcpy(&s, &u, sizeof s);
  return static_cast<double>(s);
}

// Decodes `count` values of `type` from `p` (byte order of `r`).
void decode(const Reader& r, std::uint16_t type, std::uint64_t count, const unsigned char* p,
            TiffTag& out) {
  if (type == kAscii || type == 7) {
    for (std::uint64_t k = 0; k < count && p[k] != 0; ++k) out.text.push_back(char(p[k]));
    return;
  }
  const int n = type_size(type);
  out.numbers.reserve(count);
  for (std::uint64_t k = 0; k < count; ++k, p += n) {
    switch (type) {
      case 1:
      case 3:
      case 4:
      case 16:
        out.numbers.push_back(double(r.value(p, n)));
        break;
      case 6:
        out.numbers.push_back(as_signed<std::int8_t>(std::uint8_t(r.value(p, 1))));
        break;
      case 8:
        out.numbers.push_back(as_signed<std::int16_t>(std::uint16_t(r.value(p, 2))));
        break;
      case 9:
        out.numbers.push_back(as_signed<std::int32_t>(std::uint32_t(r.value(p, 4))));
        break;
      case 17:
        out.numbers.push_back(as_signed<std::int64_t>(r.value(p, 8)));
        break;
      case 11: {
        const auto u = std::uint32_t(r.value(p, 4));
        float f;
        std::memcpy(&f, &u, 4);
        out.numbers.push_back(f);
        break;
      }
      case 12: {
        const std::uint64_t u = r.value(p, 8);
        double d;
        std::memcpy(&d, &u, 8);
        out.numbers.push_back(d);
        break;
      }
      case 5:
      case 10: {
        const auto num = std::uint32_t(r.value(p, 4)), den = std::uint32_t(r.value(p + 4, 4));
        const double a = type == 5 ? double(num) : as_signed<std::int32_t>(num);
        const double b = type == 5 ? double(den) : as_signed<std::int32_t>(den);
        out.numbers.push_back(a / b);  // 0/0 is NaN: the users check finiteness
        break;
      }
      default:
        break;
    }
  }
}

}  // namespace

Result<std::optional<std::vector<TiffTag>>> read_tiff_tags(const ReadAt& read, std::uint64_t size,
                                                           std::span<const std::uint16_t> wanted,
                                                           std::uint64_t max_values) {
  using Tags = std::optional<std::vector<TiffTag>>;
  unsigned char head[16];
  if (size < 8 || !read(0, 8, head)) return Tags{};
  const bool little = head[0] == 'I' && head[1] == 'I';
  if (!little && !(head[0] == 'M' && head[1] == 'M')) return Tags{};
  Reader r{read, size, little};
  const std::uint64_t magic = r.value(head + 2, 2);
  if (magic != 42 && magic != 43) return Tags{};
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
  std::vector<TiffTag> found;
  unsigned char e[20];
  for (std::uint64_t k = 0; k < entries; ++k) {
    const std::uint64_t at = ifd + std::uint64_t(head_size) + k * std::uint64_t(entry_size);
    if (!r.bytes(at, std::size_t(entry_size), e))
      return Error{"IFD entry " + std::to_string(k) + " lies outside the file"};
    const auto tag = static_cast<std::uint16_t>(r.value(e, 2));
    if (std::find(wanted.begin(), wanted.end(), tag) == wanted.end()) continue;
    TiffTag t;
    t.tag = tag;
    t.type = static_cast<std::uint16_t>(r.value(e + 2, 2));
    t.count = r.value(e + 4, count_size);
    const int n = type_size(t.type);
    if (n == 0) {
      t.error = "type " + std::to_string(t.type) + " is not read";
    } else if (t.count > max_values) {
      t.error = "holds " + std::to_string(t.count) + " values (at most " +
                std::to_string(max_values) + " are read)";
    } else {
      const std::uint64_t bytes = t.count * std::uint64_t(n);  // <= max_values * 8: no overflow
      const unsigned char* inline_value = e + 4 + count_size;
      if (bytes <= std::uint64_t(count_size)) {
        decode(r, t.type, t.count, inline_value, t);
      } else {
        const std::uint64_t off = r.value(inline_value, count_size);
        std::vector<unsigned char> buf(bytes);
        if (!r.bytes(off, std::size_t(bytes), buf.data()))
          t.error = "value (" + std::to_string(bytes) + " bytes at offset " + std::to_string(off) +
                    ") lies outside the file";
        else
          decode(r, t.type, t.count, buf.data(), t);
      }
    }
    found.push_back(std::move(t));
  }
  return Tags{std::move(found)};
}

Result<std::optional<std::vector<TiffTag>>> read_tiff_tags_file(
    const std::string& path, std::span<const std::uint16_t> wanted, std::uint64_t max_values) {
  using Tags = std::optional<std::vector<TiffTag>>;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!f) return Tags{};
  if (std::fseek(f.get(), 0, SEEK_END) != 0) return Tags{};
  const long end = std::ftell(f.get());
  if (end < 0) return Tags{};
  ReadAt read = [&](std::uint64_t offset, std::size_t n, unsigned char* out) {
    if (offset > std::uint64_t(end)) return false;
    if (std::fseek(f.get(), static_cast<long>(offset), SEEK_SET) != 0) return false;
    return std::fread(out, 1, n, f.get()) == n;
  };
  return read_tiff_tags(read, std::uint64_t(end), wanted, max_values);
}

const TiffTag* find_tag(const std::vector<TiffTag>& tags, std::uint16_t tag) {
  for (const TiffTag& t : tags)
    if (t.tag == tag) return &t;
  return nullptr;
}

Result<std::optional<std::string>> gdal_nodata_text(const std::vector<TiffTag>& tags) {
  const TiffTag* t = find_tag(tags, kTagGdalNodata);
  if (t == nullptr) return std::optional<std::string>{};
  if (t->type != kAscii)
    return Error{"GDAL_NODATA tag has type " + std::to_string(t->type) + "; expected 2 (ASCII)"};
  if (t->count > kMaxNodataChars)
    return Error{"GDAL_NODATA tag holds " + std::to_string(t->count) + " characters (at most " +
                 std::to_string(kMaxNodataChars) + ")"};
  if (!t->error.empty()) return Error{"GDAL_NODATA tag's " + t->error};
  std::string s = t->text;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
  std::size_t b = 0;
  while (b < s.size() && (s[b] == ' ' || s[b] == '\t')) ++b;
  return std::optional<std::string>{s.substr(b)};
}

namespace {
constexpr std::uint16_t kNodataOnly[] = {kTagGdalNodata};
}  // namespace

Result<std::optional<std::string>> read_gdal_nodata(const ReadAt& read, std::uint64_t size) {
  auto tags = read_tiff_tags(read, size, kNodataOnly, kMaxNodataChars);
  if (!tags) return tags.error();
  if (!*tags) return std::optional<std::string>{};
  return gdal_nodata_text(**tags);
}

Result<std::optional<std::string>> read_gdal_nodata_file(const std::string& path) {
  auto tags = read_tiff_tags_file(path, kNodataOnly, kMaxNodataChars);
  if (!tags) return tags.error();
  if (!*tags) return std::optional<std::string>{};
  return gdal_nodata_text(**tags);
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
