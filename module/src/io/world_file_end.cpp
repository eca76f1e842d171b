// The end of a world file (world_output.h): the chunks of page entries, the index, the TIFF
// directories of the heights and their overviews, the BigTIFF header and the locator.
#include "io/world_output.h"
#include "io/world_tiff.h"

namespace ridgeline::io::world_file {

using detail::fmt;

Status write_file_end(Output& out, const FileEnd& f) {
  // ---- page entries, in chunks read when a page of theirs is first loaded -----------------
  std::vector<std::pair<std::uint64_t, std::uint64_t>> chunks;  // offset, checksum
  for (std::size_t c0 = 0; c0 < f.entries.size(); c0 += kChunkEntries) {
    Writer cw;
    for (std::size_t k = c0; k < std::min(f.entries.size(), c0 + kChunkEntries); ++k) {
      const PageEntry& e = f.entries[k];
      cw.put(e.offset), cw.put(e.tile), cw.put(e.apron), cw.put(e.materials), cw.put(e.records);
      cw.put(e.checksum);
    }
    chunks.emplace_back(out.size(), checksum(cw.bytes.data(), cw.bytes.size()));
    if (auto st = out.write(cw.bytes.data(), cw.bytes.size()); !st) return Error{st.message()};
  }

  // ---- index ------------------------------------------------------------------------------
  Writer w;
  w.bytes.insert(w.bytes.end(), {'R', 'W', 'I', 'N', 'D', 'E', 'X', '1'});
  w.put(f.info.width), w.put(f.info.height);
  w.put(f.info.spacing_x), w.put(f.info.spacing_z), w.put(f.info.origin_x), w.put(f.info.origin_z);
  w.put(f.info.height_offset), w.put(f.info.height_scale);
  w.put(std::uint8_t(f.store_u16 ? 0 : 1));
  w.put(f.info.min_local), w.put(f.info.max_local);
  w.put(std::uint8_t(f.materials ? 1 : 0));
  w.put(f.info.filled_samples), w.put(f.info.content_hash);
  w.put_string(f.info.name);
  w.put(f.patch_exponent), w.put(f.morph_window), w.put(f.morph_delay);
  w.put(f.grid.levels);
  for (std::uint32_t k = 0; k < f.grid.levels; ++k) w.put(f.grid.px[k]), w.put(f.grid.pz[k]);
  for (const PageSummary& s : f.summaries) w.put(s.lo), w.put(s.hi), w.put(s.lo8), w.put(s.hi8);
  // Version 5: where the chunks of page entries lie (kChunkEntries a chunk) and their checksums.
  for (const auto& [at, sum] : chunks) w.put(at), w.put(sum);
  // Version 4: the holes as runs of cells along rows.
  w.put(std::uint64_t(f.hole_runs.size()));
  for (const HoleRun& r : f.hole_runs) w.put(r.j), w.put(r.i0), w.put(r.i1);
  const std::uint64_t index_at = out.size();
  if (auto s = out.write(w.bytes.data(), w.bytes.size()); !s) return Error{s.message()};

  // ---- TIFF directories: the heights and their overviews, GeoTIFF tags on the first ---------
  std::uint64_t first_ifd = 0, prev_next_at = 0;
  for (std::uint32_t k = 0; k < f.grid.levels; ++k) {
    const int ls = world::level_shift(k);
    const std::uint32_t iw = std::uint32_t(((f.info.width - 1) >> ls) + 1);
    const std::uint32_t ih = std::uint32_t(((f.info.height - 1) >> ls) + 1);
    // Tiles row by row: the pages' own, then past the last page column / row the edge tiles.
    const std::uint32_t tx = (iw + kTile - 1) / kTile, tz = (ih + kTile - 1) / kTile;
    std::vector<std::uint64_t> offsets, counts;
    for (std::uint32_t z = 0; z < tz; ++z)
      for (std::uint32_t x = 0; x < tx; ++x) {
        const std::uint32_t px = std::min<std::uint32_t>(x, std::uint32_t(f.grid.px[k]) - 1);
        const std::uint32_t pz = std::min<std::uint32_t>(z, std::uint32_t(f.grid.pz[k]) - 1);
        const std::size_t p = f.level_first[k] + px + std::size_t(pz) * std::size_t(f.grid.px[k]);
        const bool past_x = x >= std::uint32_t(f.grid.px[k]), past_z = z >= std::uint32_t(f.grid.pz[k]);
        std::pair<std::uint64_t, std::uint64_t> t{f.entries[p].offset, f.entries[p].tile};
        if (past_x || past_z) {
          auto& m = past_x && past_z ? f.edge_xz : past_x ? f.edge_x : f.edge_z;
          const auto it = m.find(p);
          if (it == m.end())
            return Error{fmt("bake: internal error: no edge tile for page %zu of level %u", p, k)};
          t = it->second;
        }
        offsets.push_back(t.first);
        counts.push_back(t.second);
      }
    std::vector<TiffEntry> tags = {
        entry<std::uint32_t>(254, kLong, {k == 0 ? 0u : 1u}),
        entry<std::uint32_t>(256, kLong, {iw}),
        entry<std::uint32_t>(257, kLong, {ih}),
        entry<std::uint16_t>(258, kShort, {std::uint16_t(f.store_u16 ? 16 : 32)}),
        entry<std::uint16_t>(259, kShort, {8}),
        entry<std::uint16_t>(262, kShort, {1}),
        entry<std::uint16_t>(277, kShort, {1}),
        entry<std::uint16_t>(284, kShort, {1}),
        entry<std::uint16_t>(317, kShort, {std::uint16_t(f.store_u16 ? 2 : 3)}),
        entry<std::uint32_t>(322, kLong, {kTile}),
        entry<std::uint32_t>(323, kLong, {kTile}),
        entry<std::uint64_t>(324, kLong8, offsets),
        entry<std::uint64_t>(325, kLong8, counts),
        entry<std::uint16_t>(339, kShort, {std::uint16_t(f.store_u16 ? 1 : 3)}),
    };
    if (k == 0) {
      // World x is easting and z is -northing (io.h, FilePlacement): the model's y is -z.
      tags.push_back(entry<double>(33550, kDouble, {f.info.spacing_x, f.info.spacing_z, 0.0}));
      tags.push_back(entry<double>(33922, kDouble,
                                   {0.0, 0.0, 0.0, f.info.origin_x, -f.info.origin_z, 0.0}));
      // Projected, user-defined, metres; samples at pixel centres (PixelIsPoint).
      tags.push_back(entry<std::uint16_t>(34735, kShort,
                                          {1, 1, 0, 4, 1024, 0, 1, 1, 1025, 0, 1, 2, 3072, 0,
                                           1, 32767, 3076, 0, 1, 9001}));
    }
    std::uint64_t next_at = 0;
    auto at = write_ifd(out, std::move(tags), next_at);
    if (!at) return at.error();
    if (k == 0)
      first_ifd = *at;
    else if (auto s = out.pwrite(prev_next_at, &*at, 8); !s)
      return Error{s.message()};
    prev_next_at = next_at;
  }

  // ---- header and locator -------------------------------------------------------------------
  Writer hdr;
  hdr.bytes.insert(hdr.bytes.end(), {'I', 'I', 43, 0, 8, 0, 0, 0});
  hdr.put(first_ifd);
  if (auto s = out.pwrite(0, hdr.bytes.data(), hdr.bytes.size()); !s) return Error{s.message()};
  Writer loc;
  loc.bytes.insert(loc.bytes.end(), kMagic, kMagic + 8);
  loc.put(kVersion);
  loc.put(std::uint32_t(0));
  loc.put(index_at);
  loc.put(std::uint64_t(w.bytes.size()));
  loc.put(checksum(w.bytes.data(), w.bytes.size()));
  loc.put(out.size());
  loc.put(checksum(loc.bytes.data(), 48));
  loc.bytes.resize(kLocatorBytes, 0);
  if (auto s = out.pwrite(kLocatorAt, loc.bytes.data(), loc.bytes.size()); !s)
    return Error{s.message()};
  return {};
}

}  // namespace ridgeline::io::world_file
