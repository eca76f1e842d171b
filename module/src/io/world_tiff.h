// Private: the TIFF side of a world file (world_format.h): BigTIFF directory entries and the
// writing of one image file directory, used by the bake (world_writer.cpp).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

#include "io/world_format.h"
#include "ridgeline/result.h"

namespace ridgeline::io::world_file {

// TIFF directory entry types (BigTIFF).
inline constexpr std::uint16_t kShort = 3, kLong = 4, kDouble = 12, kLong8 = 16;

struct TiffEntry {
  std::uint16_t tag, type;
  std::uint64_t count;
  std::vector<std::uint8_t> data;  // count values of the type
};

template <class T>
TiffEntry entry(std::uint16_t tag, std::uint16_t type, const std::vector<T>& values) {
  TiffEntry e{tag, type, values.size(), {}};
  e.data.resize(values.size() * sizeof(T));
  std::memcpy(e.data.data(), values.data(), e.data.size());
  return e;
}

// Writes one BigTIFF directory (its out-of-line values first) at the end of `out`; returns its
// offset. `next_at` receives where its next-directory offset lies.
// Writes one image file directory (values over 8 bytes first, word-aligned) through `out`
// (size() and write(data, n)); `next_at` receives where its next-directory offset lies.
template <class Out>
Result<std::uint64_t> write_ifd(Out& out, std::vector<TiffEntry> entries, std::uint64_t& next_at) {
  std::sort(entries.begin(), entries.end(),
            [](const TiffEntry& a, const TiffEntry& b) { return a.tag < b.tag; });
  std::vector<std::uint64_t> value_at(entries.size(), 0);
  for (std::size_t k = 0; k < entries.size(); ++k)
    if (entries[k].data.size() > 8) {
      std::uint64_t at = out.size();
      if (at & 1) {
        const std::uint8_t zero = 0;
        if (auto s = out.write(&zero, 1); !s) return Error{s.message()};
        ++at;
      }
      value_at[k] = at;
      if (auto s = out.write(entries[k].data.data(), entries[k].data.size()); !s)
        return Error{s.message()};
    }
  Writer w;
  w.put(std::uint64_t(entries.size()));
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const TiffEntry& e = entries[k];
    w.put(e.tag);
    w.put(e.type);
    w.put(e.count);
    std::uint8_t inline_value[8] = {};
    if (e.data.size() <= 8)
      std::memcpy(inline_value, e.data.data(), e.data.size());
    else
      std::memcpy(inline_value, &value_at[k], 8);
    w.bytes.insert(w.bytes.end(), inline_value, inline_value + 8);
  }
  std::uint64_t ifd_at = out.size();
  if (ifd_at & 1) {
    const std::uint8_t zero = 0;
    if (auto s = out.write(&zero, 1); !s) return Error{s.message()};
    ++ifd_at;
  }
  next_at = ifd_at + w.bytes.size();
  w.put(std::uint64_t(0));
  if (auto s = out.write(w.bytes.data(), w.bytes.size()); !s) return Error{s.message()};
  return ifd_at;
}

}  // namespace ridgeline::io::world_file
