// The baked world's reader (world_file.h, world_format.h): a PageSource over a world file.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <span>

#include "format.h"
#include "io/world_format.h"
#include "ridgeline/world_file.h"
#include "world/page.h"

namespace ridgeline::io {

using detail::fmt;
using namespace world_file;

namespace {

class WorldSource final : public PageSource {
 public:
  ~WorldSource() override {
    if (fd_ >= 0) ::close(fd_);
  }
  const WorldInfo& info() const noexcept override { return info_; }
  BakedRecords baked_records() const noexcept override { return baked_; }
  Status summaries(std::vector<PageSummary>& out) const override;
  Status load(const PageKey& key, PageData& out) const override;
  Status holes(std::vector<HoleRun>& out) const override {
    out = holes_;
    return {};
  }

  static Result<std::shared_ptr<const PageSource>> open(const std::string& path);

 private:
  Status read_at(std::uint64_t offset, void* into, std::size_t n) const;
  /// The kEntryBytes of page `slot`'s entry: in the index (versions 3 and 4), or in its chunk,
  /// read and checked on first use (version 5).
  Result<const std::uint8_t*> entry_bytes(std::size_t slot) const;
  std::string name_;
  int fd_ = -1;
  std::uint64_t file_bytes_ = 0;
  WorldInfo info_;
  BakedRecords baked_;
  world::PageGrid grid_;
  std::vector<std::size_t> level_first_;  // index of each level's first page
  // The index as read (its checksum checked at the open). The page summaries and the page
  // entries are read from it when asked for: the open does nothing per page but the checksum.
  std::unique_ptr<std::uint8_t[]> index_;
  std::size_t summaries_at_ = 0, entries_at_ = 0;  // where they start in index_
  std::size_t page_count_ = 0;
  std::uint64_t data_end_ = 0;
  std::vector<HoleRun> holes_;
  // Version 5: the chunks of page entries (offset, checksum) and those read so far (loads run on
  // several threads; a chunk, once read, is never freed or moved).
  struct Chunk {
    std::uint64_t offset = 0, checksum = 0;
    std::unique_ptr<std::uint8_t[]> bytes;
  };
  mutable std::vector<Chunk> chunks_;
  mutable std::mutex chunks_mu_;
};

Status WorldSource::read_at(std::uint64_t offset, void* into, std::size_t n) const {
  auto* p = static_cast<std::uint8_t*>(into);
  std::size_t done = 0;
  while (done < n) {
    const ssize_t r = ::pread(fd_, p + done, n - done, off_t(offset + done));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) return Error{fmt("%s: read failed (%s)", name_.c_str(), std::strerror(errno))};
    if (r == 0)
      return Error{fmt("%s: truncated (ends before byte %llu)", name_.c_str(),
                       static_cast<unsigned long long>(offset + n))};
    done += std::size_t(r);
  }
  return {};
}

Result<std::shared_ptr<const PageSource>> WorldSource::open(const std::string& path) {
  auto s = std::make_shared<WorldSource>();
  s->name_ = "world '" + path + "'";
  s->fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (s->fd_ < 0) return Error{fmt("%s: %s", s->name_.c_str(), std::strerror(errno))};
  struct stat st {};
  if (::fstat(s->fd_, &st) != 0)
    return Error{fmt("%s: %s", s->name_.c_str(), std::strerror(errno))};
  s->file_bytes_ = std::uint64_t(st.st_size);
  if (s->file_bytes_ < kDataStart)
    return Error{fmt("%s: %llu bytes; not a Ridgeline world (too short for its header)",
                     s->name_.c_str(), static_cast<unsigned long long>(s->file_bytes_))};
  std::uint8_t head[kDataStart];
  if (auto r = s->read_at(0, head, sizeof head); !r) return Error{r.message()};
  if (!(head[0] == 'I' && head[1] == 'I' && head[2] == 43 && head[3] == 0))
    return Error{fmt("%s: not a Ridgeline world (not a little-endian BigTIFF)", s->name_.c_str())};
  const std::uint8_t* loc = head + kLocatorAt;
  if (std::memcmp(loc, kMagic, 8) != 0)
    return Error{fmt("%s: a TIFF, but not a Ridgeline world (no locator: bake it with ridge bake)",
                     s->name_.c_str())};
  Reader lr{std::span<const std::uint8_t>(loc + 8, kLocatorBytes - 8)};
  const auto version = lr.get<std::uint32_t>();
  lr.get<std::uint32_t>();
  const auto index_at = lr.get<std::uint64_t>();
  const auto index_bytes = lr.get<std::uint64_t>();
  const auto index_sum = lr.get<std::uint64_t>();
  const auto data_end = lr.get<std::uint64_t>();
  const auto loc_sum = lr.get<std::uint64_t>();
  if (version < kOldestVersion || version > kVersion)
    return Error{fmt("%s: format version %u; this build reads versions %u to %u (bake it again)",
                     s->name_.c_str(), version, kOldestVersion, kVersion)};
  if (loc_sum != checksum(loc, 48))
    return Error{fmt("%s: its header is corrupted (checksum mismatch)", s->name_.c_str())};
  if (data_end > s->file_bytes_)
    return Error{fmt("%s: truncated (%llu bytes of %llu)", s->name_.c_str(),
                     static_cast<unsigned long long>(s->file_bytes_),
                     static_cast<unsigned long long>(data_end))};
  if (index_at < kDataStart || index_bytes > (std::uint64_t{1} << 34) ||
      index_at + index_bytes > data_end)
    return Error{fmt("%s: its index lies outside the file (corrupted)", s->name_.c_str())};
  // Not value-initialised: the read fills it.
  s->index_.reset(new std::uint8_t[std::size_t(index_bytes)]);
  s->data_end_ = data_end;
  const std::span<const std::uint8_t> index(s->index_.get(), std::size_t(index_bytes));
  if (auto r = s->read_at(index_at, s->index_.get(), index.size()); !r)
    return Error{r.message()};
  if (checksum(index.data(), index.size()) != index_sum)
    return Error{fmt("%s: its index is corrupted (checksum mismatch)", s->name_.c_str())};
  Reader in{index};
  char magic[8];
  for (char& c : magic) c = char(in.get<std::uint8_t>());
  if (std::memcmp(magic, "RWINDEX1", 8) != 0)
    return Error{fmt("%s: its index is corrupted (bad magic)", s->name_.c_str())};
  WorldInfo& w = s->info_;
  w.width = in.get<std::uint32_t>();
  w.height = in.get<std::uint32_t>();
  w.spacing_x = in.get<double>();
  w.spacing_z = in.get<double>();
  w.origin_x = in.get<double>();
  w.origin_z = in.get<double>();
  w.height_offset = in.get<double>();
  w.height_scale = in.get<double>();
  const auto fmt_byte = in.get<std::uint8_t>();
  w.format = fmt_byte == 0 ? SampleFormat::kU16 : SampleFormat::kF32;
  w.min_local = in.get<float>();
  w.max_local = in.get<float>();
  w.has_materials = in.get<std::uint8_t>() != 0;
  w.filled_samples = in.get<std::uint64_t>();
  w.content_hash = in.get<std::uint64_t>();
  const std::string name = in.get_string(4096);
  w.name = s->name_;
  s->baked_.patch_exponent = in.get<std::uint32_t>();
  s->baked_.morph_window = in.get<double>();
  s->baked_.morph_delay = in.get<double>();
  const auto levels = in.get<std::uint32_t>();
  HeightfieldDesc d;
  d.width = w.width, d.height = w.height;
  d.spacing_x = w.spacing_x, d.spacing_z = w.spacing_z;
  d.origin_x = w.origin_x, d.origin_z = w.origin_z;
  d.height_offset = w.height_offset;
  d.height_scale = w.height_scale > 0 ? w.height_scale : 1.0;
  d.max_samples = ~std::uint64_t{0};
  d.name = s->name_;
  if (!in.ok() || fmt_byte > 1) return Error{fmt("%s: its index is corrupted", s->name_.c_str())};
  // The tessellator settings the bounds were baked for, as Landscape::create checks a request.
  const BakedRecords& br = s->baked_;
  if ((br.patch_exponent != 0 && (br.patch_exponent < 2 || br.patch_exponent > 10)) ||
      !(br.morph_window >= 0.0 && br.morph_window <= 4.0) ||
      !(br.morph_delay >= 0.0 && br.morph_delay <= 1.0))
    return Error{fmt("%s: its baked tessellator settings are corrupted (patch exponent %u, morph "
                     "window %s, delay %s)",
                     s->name_.c_str(), br.patch_exponent, detail::num(br.morph_window).c_str(),
                     detail::num(br.morph_delay).c_str())};
  if (auto st2 = validate_heightfield_desc(d); !st2) return Error{st2.message()};
  if (!std::isfinite(w.min_local) || !std::isfinite(w.max_local) || w.min_local > w.max_local)
    return Error{fmt("%s: its height range is corrupted", s->name_.c_str())};
  s->grid_ = world::PageGrid::of(w.width, w.height);
  if (levels != s->grid_.levels)
    return Error{fmt("%s: %u page levels; a %u x %u world has %u (corrupted)", s->name_.c_str(),
                     levels, w.width, w.height, s->grid_.levels)};
  std::size_t total = 0;
  for (std::uint32_t k = 0; k < levels; ++k) {
    const auto px = in.get<std::int32_t>(), pz = in.get<std::int32_t>();
    if (px != s->grid_.px[k] || pz != s->grid_.pz[k])
      return Error{fmt("%s: level %u has %d x %d pages; need %d x %d (corrupted)",
                       s->name_.c_str(), k, px, pz, s->grid_.px[k], s->grid_.pz[k])};
    s->level_first_.push_back(total);
    total += s->grid_.count(k);
  }
  // The summaries (16 bytes a level-0 page), read and checked when asked for (summaries()); the
  // page entries (kEntryBytes a page) when a page is loaded: in the index up to version 4, in
  // chunks outside it from version 5 (the index holds their offsets and checksums).
  const std::size_t chunk_count = (total + kChunkEntries - 1) / kChunkEntries;
  const std::size_t summary_bytes = 16 * s->grid_.count(0);
  const std::size_t entry_bytes = version >= 5 ? 16 * chunk_count : kEntryBytes * total;
  if (!in.ok() || index.size() - in.at < summary_bytes ||
      index.size() - in.at - summary_bytes < entry_bytes)
    return Error{fmt("%s: its index has too few bytes (corrupted)", s->name_.c_str())};
  s->summaries_at_ = in.at;
  s->entries_at_ = in.at + summary_bytes;
  s->page_count_ = total;
  in.at += summary_bytes;
  if (version >= 5) {
    s->chunks_.resize(chunk_count);
    for (std::size_t c = 0; c < chunk_count; ++c) {
      Chunk& ch = s->chunks_[c];
      ch.offset = in.get<std::uint64_t>();
      ch.checksum = in.get<std::uint64_t>();
      const std::size_t n = kEntryBytes * std::min(kChunkEntries, total - c * kChunkEntries);
      if (ch.offset < kDataStart || ch.offset > data_end || n > data_end - ch.offset)
        return Error{fmt("%s: page entry chunk %zu lies outside the file (corrupted)",
                         s->name_.c_str(), c)};
    }
  } else {
    in.at += entry_bytes;
  }
  if (version >= 4) {
    // The holes: runs along rows of cells, inside the cells, in order and apart.
    const auto runs = in.get<std::uint64_t>();
    if (!in.ok() || runs > (index.size() - std::min(in.at, index.size())) / 12)
      return Error{fmt("%s: its hole list is corrupted", s->name_.c_str())};
    s->holes_.resize(std::size_t(runs));
    for (std::size_t k = 0; k < s->holes_.size(); ++k) {
      HoleRun& r = s->holes_[k];
      r.j = in.get<std::uint32_t>(), r.i0 = in.get<std::uint32_t>(), r.i1 = in.get<std::uint32_t>();
      const bool after = k == 0 || r.j > s->holes_[k - 1].j ||
                         (r.j == s->holes_[k - 1].j && r.i0 > s->holes_[k - 1].i1 + 1);
      if (!in.ok() || r.i0 > r.i1 || r.i1 + 1 >= w.width || r.j + 1 >= w.height || !after)
        return Error{fmt("%s: hole run %zu is corrupted (row %u, cells %u .. %u of %u x %u)",
                         s->name_.c_str(), k, r.j, r.i0, r.i1, w.width - 1, w.height - 1)};
    }
  }
  if (!in.ok() || in.at != index.size())
    return Error{fmt("%s: its index has %s bytes (corrupted)", s->name_.c_str(),
                     in.ok() ? "trailing" : "too few")};
  (void)name;
  return std::shared_ptr<const PageSource>(std::move(s));
}

Result<const std::uint8_t*> WorldSource::entry_bytes(std::size_t slot) const {
  if (chunks_.empty()) return index_.get() + entries_at_ + kEntryBytes * slot;
  const std::size_t c = slot / kChunkEntries;
  std::lock_guard lock(chunks_mu_);
  Chunk& ch = chunks_[c];
  if (!ch.bytes) {
    const std::size_t n = kEntryBytes * std::min(kChunkEntries, page_count_ - c * kChunkEntries);
    std::unique_ptr<std::uint8_t[]> b(new std::uint8_t[n]);
    if (auto r = read_at(ch.offset, b.get(), n); !r) return Error{r.message()};
    if (checksum(b.get(), n) != ch.checksum)
      return Error{fmt("%s: page entry chunk %zu is corrupted (checksum mismatch)", name_.c_str(),
                       c)};
    ch.bytes = std::move(b);
  }
  return ch.bytes.get() + kEntryBytes * (slot % kChunkEntries);
}

Status WorldSource::summaries(std::vector<PageSummary>& out) const {
  const std::size_t n = grid_.count(0);
  out.resize(n);
  Reader in{std::span<const std::uint8_t>(index_.get() + summaries_at_, 16 * n)};
  for (PageSummary& m : out) {
    m.lo = in.get<float>(), m.hi = in.get<float>(), m.lo8 = in.get<float>(), m.hi8 = in.get<float>();
    if (!(m.lo <= m.hi) || !(m.lo8 <= m.hi8))
      return Error{fmt("%s: a page summary is corrupted", name_.c_str())};
  }
  return {};
}

Status WorldSource::load(const PageKey& key, PageData& out) const {
  if (key.level >= grid_.levels || key.px < 0 || key.pz < 0 || key.px >= grid_.px[key.level] ||
      key.pz >= grid_.pz[key.level])
    return Error{fmt("%s: no page (%u, %d, %d)", name_.c_str(), key.level, key.px, key.pz)};
  const std::size_t slot = level_first_[key.level] + std::size_t(key.px) +
                      std::size_t(key.pz) * std::size_t(grid_.px[key.level]);
  const auto entry = entry_bytes(slot);
  if (!entry) return Error{entry.error().message};
  Reader in{std::span<const std::uint8_t>(*entry, kEntryBytes)};
  PageEntry e;
  e.offset = in.get<std::uint64_t>();
  e.tile = in.get<std::uint32_t>();
  e.apron = in.get<std::uint32_t>();
  e.materials = in.get<std::uint32_t>();
  e.records = in.get<std::uint32_t>();
  e.checksum = in.get<std::uint64_t>();
  if (e.offset < kDataStart || e.offset > data_end_ || e.bytes() > data_end_ - e.offset)
    return Error{fmt("%s: page (%u, %d, %d) lies outside the file (corrupted)", name_.c_str(),
                     key.level, key.px, key.pz)};
  // A page's four parts compressed: at most about 0.7 MB (float heights and bounds that do not
  // compress at all); more is a damaged entry.
  constexpr std::uint64_t kMaxPageBytes = std::uint64_t{4} << 20;
  if (e.bytes() > kMaxPageBytes)
    return Error{fmt("%s: page (%u, %d, %d) claims %llu bytes (corrupted)", name_.c_str(),
                     key.level, key.px, key.pz, static_cast<unsigned long long>(e.bytes()))};
  // The page's bytes and its decompressed tile and apron are read into buffers kept per loading
  // thread: fresh buffers of this size were zeroed, then faulted in from the system, on every
  // load.
  thread_local std::vector<std::uint8_t> bytes, tile, apron;
  thread_local std::vector<float> tile_f32;
  bytes.resize(e.bytes());
  if (auto r = read_at(e.offset, bytes.data(), bytes.size()); !r) return r;
  if (checksum(bytes.data(), bytes.size()) != e.checksum)
    return Error{fmt("%s: page (%u, %d, %d) is corrupted (checksum mismatch)", name_.c_str(),
                     key.level, key.px, key.pz)};
  const bool u16 = info_.format == SampleFormat::kU16;
  const std::size_t sample_bytes = u16 ? 2 : 4;
  tile.resize(kTileSamples * sample_bytes);
  apron.resize(kApronSamples * sample_bytes);
  const std::uint8_t* p = bytes.data();
  auto bad = [&](const char* part) {
    return Error{fmt("%s: page (%u, %d, %d): its %s does not decompress (corrupted)",
                     name_.c_str(), key.level, key.px, key.pz, part)};
  };
  if (!inflate({p, e.tile}, tile)) return bad("tile");
  p += e.tile;
  if (!inflate({p, e.apron}, apron)) return bad("apron");
  p += e.apron;
  // The tile and the ring around it into the page's entries.
  auto place = [&](auto* dst, const auto* t, const auto* ring) {
    std::size_t k = 0;
    for (std::int32_t b = -kPageApron; b <= kPageCells + kPageApron; ++b)
      for (std::int32_t a = -kPageApron; a <= kPageCells + kPageApron; ++a) {
        const std::size_t e2 = world::entry_index(a, b);
        if (a >= 0 && b >= 0 && a < std::int32_t(kTile) && b < std::int32_t(kTile))
          dst[e2] = t[std::size_t(a) + std::size_t(b) * kTile];
        else
          dst[e2] = ring[k++];
      }
  };
  if (u16) {
    auto* t = reinterpret_cast<std::uint16_t*>(tile.data());
    decode_u16(t);
    out.u16.resize(kPageEntries);
    out.f32.clear();
    place(out.u16.data(), t, reinterpret_cast<const std::uint16_t*>(apron.data()));
  } else {
    std::vector<float>& t = tile_f32;
    t.resize(kTileSamples);
    decode_f32(tile.data(), t.data());
    out.f32.resize(kPageEntries);
    out.u16.clear();
    place(out.f32.data(), t.data(), reinterpret_cast<const float*>(apron.data()));
  }
  out.materials.clear();
  if (e.materials > 0) {
    out.materials.resize(kPageEntries);
    if (!inflate({p, e.materials}, out.materials)) return bad("materials");
  }
  p += e.materials;
  out.records.clear();
  if (e.records > 0) {
    // Inflated to its stated size, at most that of the largest block (the tessellator checks
    // the exact size): allocated exactly, as the page keeps it.
    constexpr std::size_t kMaxRecordBytes = 8 + kPageEntries * 4;
    std::uint32_t raw = 0;
    // The record part starts with its raw size (4 bytes), then the Deflate stream.
    if (e.records < 4) return bad("tessellator bounds");
    std::memcpy(&raw, p, 4);
    if (raw > kMaxRecordBytes) return bad("tessellator bounds");
    std::vector<std::uint8_t> rec(raw);
    if (!inflate({p + 4, e.records - 4}, rec)) return bad("tessellator bounds");
    out.records = std::move(rec);
  }
  return {};
}

}  // namespace

Result<std::shared_ptr<const PageSource>> open_world(const std::string& path) {
  return WorldSource::open(path);
}

}  // namespace ridgeline::io
