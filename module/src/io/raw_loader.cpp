// Headerless little-endian raw heightmaps (u16 or f32) of an explicitly given size.
#include <bit>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "format.h"
#include "io/loader_common.h"

namespace ridgeline::io {

namespace {

std::size_t sample_bytes(RawType type) {
  return type == RawType::kU16 ? 2 : 4;
}
const char* type_name(RawType type) {
  return type == RawType::kU16 ? "u16" : "f32";
}

HeightfieldDesc raw_desc(const RawFormat& format, const LoadOptions& options,
                         const std::string& name) {
  HeightfieldDesc desc = options.placement;
  desc.width = format.width;
  desc.height = format.height;
  desc.name = name;
  return desc;
}

Status check_size(std::uint64_t actual, const RawFormat& format, const std::string& name) {
  // validate_heightfield_desc has bounded width * height by the cap, so this cannot overflow.
  const std::uint64_t expected =
      std::uint64_t{format.width} * format.height * sample_bytes(format.type);
  if (actual != expected)
    return Error{fmt("%s: file is %llu bytes but %u x %u %s samples need %llu bytes", name.c_str(),
                     static_cast<unsigned long long>(actual), format.width, format.height,
                     type_name(format.type), static_cast<unsigned long long>(expected))};
  return {};
}

}  // namespace

Result<RawType> parse_raw_type(const std::string& text) {
  if (text == "u16") return RawType::kU16;
  if (text == "f32") return RawType::kF32;
  return Error{"raw sample type '" + text + "': expected u16 or f32"};
}

Result<Heightfield> parse_raw(std::span<const std::byte> bytes, const RawFormat& format,
                              const LoadOptions& options, const std::string& name,
                              LoadReport* report) {
  if (report != nullptr) report->pixel_type = type_name(format.type);
  const HeightfieldDesc desc = raw_desc(format, options, name);
  if (auto s = validate_heightfield_desc(desc); !s) return Error{s.message()};
  if (auto s = check_size(bytes.size(), format, name); !s) return Error{s.message()};
  const std::size_t count = std::size_t{format.width} * format.height;
  std::vector<float> values(count);
  const auto* b = reinterpret_cast<const unsigned char*>(bytes.data());
  // Assembled byte by byte: little-endian whatever the host is.
  if (format.type == RawType::kU16) {
    for (std::size_t k = 0; k < count; ++k)
      values[k] = static_cast<float>(b[2 * k] | (b[2 * k + 1] << 8));
  } else {
    for (std::size_t k = 0; k < count; ++k) {
      const unsigned char* p = b + 4 * k;
      const std::uint32_t u = std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) |
                              (std::uint32_t{p[2]} << 16) | (std::uint32_t{p[3]} << 24);
      values[k] = std::bit_cast<float>(u);
    }
  }
  return detail::finish_heightfield(desc, values, options, report);
}

Result<Heightfield> load_raw(const std::string& path, const RawFormat& format,
                             const LoadOptions& options, LoadReport* report) {
  const std::string name = detail::heightmap_name(path);
  if (auto s = detail::check_regular_file(path, name); !s) return Error{s.message()};
  // The cap and the file size are checked before reading a byte.
  if (auto s = validate_heightfield_desc(raw_desc(format, options, name)); !s)
    return Error{s.message()};
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return Error{name + ": cannot get the file size: " + ec.message()};
  if (auto s = check_size(size, format, name); !s) return Error{s.message()};
  std::vector<std::byte> bytes(size);
  std::ifstream file(path, std::ios::binary);
  if (!file) return Error{name + ": cannot open: " + std::strerror(errno)};
  file.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size));
  if (static_cast<std::uint64_t>(file.gcount()) != size)
    return Error{fmt("%s: read %lld of %llu bytes (file changed while reading?)", name.c_str(),
                     static_cast<long long>(file.gcount()), static_cast<unsigned long long>(size))};
  return parse_raw(bytes, format, options, name, report);
}

}  // namespace ridgeline::io
