// PNG chunk structure (PNG specification, 3rd edition, section 5.3: length, type, data, CRC-32
// over type and data), walked without decoding.
#include "io/png_check.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

#include "format.h"

namespace ridgeline::io::detail {

namespace {

constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

// The CRC-32 of ISO 3309 / ITU-T V.42 (polynomial 0xedb88320, reflected), by table.
constexpr std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> t{};
  for (std::uint32_t n = 0; n < 256; ++n) {
    std::uint32_t c = n;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
    t[n] = c;
  }
  return t;
}
constexpr std::array<std::uint32_t, 256> kCrcTable = make_crc_table();

std::uint32_t crc_update(std::uint32_t crc, const unsigned char* p, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) crc = kCrcTable[(crc ^ p[k]) & 0xff] ^ (crc >> 8);
  return crc;
}

std::uint32_t be32(const unsigned char* p) {
  return (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) |
         std::uint32_t(p[3]);
}

// The chunk type for messages: its four letters, or hex escapes for other bytes.
std::string type_name(const unsigned char* t) {
  std::string s;
  for (int k = 0; k < 4; ++k) {
    if ((t[k] >= 'A' && t[k] <= 'Z') || (t[k] >= 'a' && t[k] <= 'z'))
      s += char(t[k]);
    else
      s += fmt("\\x%02x", unsigned(t[k]));
  }
  return s;
}

}  // namespace

Status check_png_chunks(const std::string& path, const std::string& name) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};  // the reader reports it
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0);
  unsigned char head[8];
  if (size < 8 || !in.read(reinterpret_cast<char*>(head), 8) ||
      std::memcmp(head, kSignature, 8) != 0)
    return {};
  std::vector<unsigned char> buf(std::size_t{1} << 16);
  std::uint64_t at = 8;
  for (int chunk = 0;; ++chunk) {
    if (at == size)
      return Error{fmt("%s: truncated PNG file: it ends after %llu bytes, before its IEND chunk",
                       name.c_str(), static_cast<unsigned long long>(size))};
    unsigned char h[8];
    if (size - at < 8 || !in.read(reinterpret_cast<char*>(h), 8))
      return Error{
          fmt("%s: truncated PNG file: it ends inside the header of chunk %d at byte "
              "%llu (%llu bytes in all)",
              name.c_str(), chunk + 1, static_cast<unsigned long long>(at),
              static_cast<unsigned long long>(size))};
    const std::uint32_t length = be32(h);
    const std::string type = type_name(h + 4);
    // A chunk is 12 bytes of frame around its data.
    if (length > 0x7fffffffu || std::uint64_t(length) + 12 > size - at)
      return Error{
          fmt("%s: truncated PNG file: chunk '%s' at byte %llu needs %llu bytes, the "
              "file ends %llu bytes after its start (%llu bytes in all)",
              name.c_str(), type.c_str(), static_cast<unsigned long long>(at),
              static_cast<unsigned long long>(std::uint64_t(length) + 12),
              static_cast<unsigned long long>(size - at), static_cast<unsigned long long>(size))};
    std::uint32_t crc = crc_update(0xffffffffu, h + 4, 4);
    for (std::uint32_t left = length; left > 0;) {
      const std::size_t n = std::min<std::size_t>(left, buf.size());
      if (!in.read(reinterpret_cast<char*>(buf.data()), std::streamsize(n)))
        return Error{name + ": cannot read the file"};
      crc = crc_update(crc, buf.data(), n);
      left -= std::uint32_t(n);
    }
    unsigned char stored[4];
    if (!in.read(reinterpret_cast<char*>(stored), 4)) return Error{name + ": cannot read the file"};
    if ((crc ^ 0xffffffffu) != be32(stored))
      return Error{
          fmt("%s: corrupt PNG file: chunk '%s' at byte %llu (%u bytes of data) fails "
              "its CRC check",
              name.c_str(), type.c_str(), static_cast<unsigned long long>(at), length)};
    at += std::uint64_t(length) + 12;
    if (std::memcmp(h + 4, "IEND", 4) == 0) return {};
  }
}

}  // namespace ridgeline::io::detail
