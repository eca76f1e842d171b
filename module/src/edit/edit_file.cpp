// The edit layer's file (docs/deformation.md, "The edit file"): a versioned, checksummed binary
// image of every edited chunk, written to a sink and read back from a source as one
// transaction. No file system here: Ridgeline::io (io/edit_file.cpp) gives files.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "edit/sample_changes.h"
#include "format.h"
#include "ridgeline/edit.h"
#include "surface/edit_layer.h"
#include "surface/lattice.h"

namespace ridgeline {

static_assert(std::endian::native == std::endian::little,
              "the edit file is little-endian and read by memcpy");

namespace {

constexpr char kMagic[8] = {'R', 'I', 'D', 'G', 'E', 'E', 'D', 'T'};
// 2: the terrain hash a file records is the page-wise content hash (version 1 recorded an older
// hash of the same samples, which no build computes any more). 3: the hole mask, in blocks after
// the chunks, counted at offset 48 (0 in a version 2 file, which is read as one without holes).
constexpr std::uint32_t kVersion = 3;
constexpr std::size_t kHeaderBytes = 64;
constexpr std::size_t kChunkValues = std::size_t{EditLayer::kChunk} * EditLayer::kChunk;
constexpr std::size_t kChunkBytes = 8 + 4 * kChunkValues;
constexpr std::size_t kHoleBytes = 8 + sizeof(HoleMask::Bits);  // bx, bz, 32 x 32 bits

// Hole blocks along x and z of a terrain (its cells, not its samples).
std::uint64_t hole_blocks_x(const WorldInfo& hf) {
  return (std::uint64_t(hf.width) - 1 + HoleMask::kBlock - 1) / HoleMask::kBlock;
}
std::uint64_t hole_blocks_z(const WorldInfo& hf) {
  return (std::uint64_t(hf.height) - 1 + HoleMask::kBlock - 1) / HoleMask::kBlock;
}

constexpr std::uint64_t kFnvBasis = 1469598103934665603ull;

std::uint64_t fnv1a(const char* p, std::size_t n, std::uint64_t h = kFnvBasis) {
  for (std::size_t k = 0; k < n; ++k) {
    h ^= static_cast<unsigned char>(p[k]);
    h *= 1099511628211ull;
  }
  return h;
}

template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
T get(std::string_view in, std::size_t at) {
  T v;
  std::memcpy(&v, in.data() + at, sizeof v);
  return v;
}

// The largest edit file of a terrain of width x height samples (every chunk edited).
std::size_t max_file_bytes(const WorldInfo& hf) {
  const std::size_t chunks = std::size_t((hf.width + EditLayer::kChunk - 1) / EditLayer::kChunk) *
                             ((hf.height + EditLayer::kChunk - 1) / EditLayer::kChunk);
  return kHeaderBytes + chunks * kChunkBytes + hole_blocks_x(hf) * hole_blocks_z(hf) * kHoleBytes +
         8;
}

// Entry n of a list of `stride`-byte entries starting at `first`, each opening with its (x, z)
// index (u32 each; chunks and hole blocks alike): inside nx x nz, after the entry before it in
// (z, x) order.
Status check_index(std::string_view in, std::size_t first, std::size_t stride, std::uint64_t n,
                   std::uint64_t nx, std::uint64_t nz, const char* kind) {
  const std::size_t at = first + n * stride;
  const auto x = get<std::uint32_t>(in, at), z = get<std::uint32_t>(in, at + 4);
  if (x >= nx || z >= nz)
    return Error{fmt("edit file: %s %llu at (%u, %u) lies outside the terrain", kind,
                     static_cast<unsigned long long>(n), x, z)};
  const auto key = [&](std::size_t a) {
    return (std::uint64_t(get<std::uint32_t>(in, a + 4)) << 32) | get<std::uint32_t>(in, a);
  };
  if (n > 0 && key(at) <= key(at - stride))
    return Error{fmt("edit file: %s %llu out of order or repeated", kind,
                     static_cast<unsigned long long>(n))};
  return {};
}

// Bytes handed to the sink at a time: at most 64 KiB (edit.h).
constexpr std::size_t kSinkBytes = std::size_t{64} << 10;

}  // namespace

Status save_edits(const Terrain& terrain, EditSink& sink) {
  const WorldInfo& hf = terrain.info();
  const detail::StoredLattice g = detail::stored_lattice(terrain.surface());
  const EditLayer& layer = terrain.edit_layer();
  const std::vector<std::uint64_t> keys = layer.sorted_keys();
  const std::shared_ptr<const HoleMask> holes = layer.hole_snapshot();
  const auto hole_blocks =
      holes ? holes->sorted_blocks() : std::vector<std::pair<std::uint64_t, HoleMask::Bits>>{};
  // The checksum runs over everything before it: hashed as each block goes out.
  std::uint64_t sum = kFnvBasis;
  std::string out;
  out.reserve(std::min(kSinkBytes, kHeaderBytes + keys.size() * kChunkBytes + 8));
  auto flush = [&]() -> Status {
    sum = fnv1a(out.data(), out.size(), sum);
    Status s = sink.write(out);
    out.clear();
    return s;
  };
  out.append(kMagic, 8);
  put(out, kVersion);
  put(out, EditLayer::kChunk);
  put(out, terrain.base_hash());
  put(out, terrain.surface().detail_hash());
  put(out, hf.width);
  put(out, hf.height);
  put(out, std::uint64_t{keys.size()});
  put(out, std::uint64_t{hole_blocks.size()});
  put(out, std::uint64_t{0});
  for (std::uint64_t k : keys) {
    if (out.size() + kChunkBytes > kSinkBytes)
      if (Status s = flush(); !s) return s;
    const std::uint32_t cx = std::uint32_t(k), cz = std::uint32_t(k >> 32);
    put(out, cx);
    put(out, cz);
    const std::uint32_t i0 = cx << EditLayer::kChunkShift, j0 = cz << EditLayer::kChunkShift;
    for (std::uint32_t dj = 0; dj < EditLayer::kChunk; ++dj)
      for (std::uint32_t di = 0; di < EditLayer::kChunk; ++di) {
        const bool in = i0 + di < hf.width && j0 + dj < hf.height;
        put(out, in ? g.local(i0 + di, j0 + dj) : 0.0f);
      }
  }
  for (const auto& [k, bits] : hole_blocks) {
    if (out.size() + kHoleBytes > kSinkBytes)
      if (Status s = flush(); !s) return s;
    put(out, std::uint32_t(k));
    put(out, std::uint32_t(k >> 32));
    put(out, bits);
  }
  if (out.size() + 8 > kSinkBytes)
    if (Status s = flush(); !s) return s;
  put(out, fnv1a(out.data(), out.size(), sum));
  return sink.write(out);
}

std::string save_edits_to_memory(const Terrain& terrain) {
  struct Memory final : EditSink {
    std::string bytes;
    Status write(std::string_view b) override {
      bytes.append(b);
      return {};
    }
  } memory;
  memory.bytes.reserve(kHeaderBytes + terrain.surface().edited_chunks() * kChunkBytes + 8 +
                       (terrain.surface().hole_cells() > 0 ? kHoleBytes : 0));
  const Status s = save_edits(terrain, memory);
  RIDGELINE_ASSERT(s.ok());  // memory never refuses
  return std::move(memory.bytes);
}

// The header fields that tie a file to a terrain (base hash, detail hash, size); `in` holds at
// least the header.
static Status check_edit_header(const Terrain& terrain, std::string_view in) {
  const WorldInfo& hf = terrain.info();
  const std::string what = "edit file";
  if (std::memcmp(in.data(), kMagic, 8) != 0)
    return Error{what + ": not a Ridgeline edit file (bad magic)"};
  const auto version = get<std::uint32_t>(in, 8);
  if (version == 1)
    return Error{what + ": version 1, written by an older build: it names its terrain by a hash "
                        "this build no longer computes; load it with that build and apply the "
                        "edits again, or re-create them"};
  if (version != kVersion && version != 2)
    return Error{fmt("%s: version %u; this build reads versions 2 and %u", what.c_str(), version,
                     kVersion)};
  if (get<std::uint32_t>(in, 12) != EditLayer::kChunk)
    return Error{fmt("%s: chunk size %u; need %u", what.c_str(), get<std::uint32_t>(in, 12),
                     EditLayer::kChunk)};
  if (get<std::uint64_t>(in, 16) != terrain.base_hash())
    return Error{
        fmt("%s: saved for another terrain (base data hash %016llx, this terrain's is "
            "%016llx)",
            what.c_str(), static_cast<unsigned long long>(get<std::uint64_t>(in, 16)),
            static_cast<unsigned long long>(terrain.base_hash()))};
  if (get<std::uint64_t>(in, 24) != terrain.surface().detail_hash())
    return Error{what + ": saved with other detail parameters (detail hash differs)"};
  if (get<std::uint32_t>(in, 32) != hf.width || get<std::uint32_t>(in, 36) != hf.height)
    return Error{fmt("%s: saved for a %u x %u terrain; this one is %u x %u", what.c_str(),
                     get<std::uint32_t>(in, 32), get<std::uint32_t>(in, 36), hf.width,
                     hf.height)};
  return {};
}

Result<EditResult> load_edits_from_memory(Terrain& terrain, std::string_view in) {
  const WorldInfo& hf = terrain.info();
  const std::string what = "edit file";
  if (in.size() < kHeaderBytes + 8)
    return Error{fmt("%s: %zu bytes; truncated (a valid file has at least %zu)", what.c_str(),
                     in.size(), kHeaderBytes + 8)};
  if (auto s = check_edit_header(terrain, in); !s) return Error{s.message()};
  const auto count = get<std::uint64_t>(in, 40);
  const std::uint64_t chunks_x = (hf.width + EditLayer::kChunk - 1) / EditLayer::kChunk;
  const std::uint64_t chunks_z = (hf.height + EditLayer::kChunk - 1) / EditLayer::kChunk;
  if (count > chunks_x * chunks_z)
    return Error{fmt("%s: %llu chunks; this terrain has only %llu", what.c_str(),
                     static_cast<unsigned long long>(count),
                     static_cast<unsigned long long>(chunks_x * chunks_z))};
  // Version 3 counts hole blocks at 48; in version 2 those bytes are reserved (0).
  const auto holes = get<std::uint64_t>(in, 48);
  const std::uint64_t blocks_x = hole_blocks_x(hf), blocks_z = hole_blocks_z(hf);
  if (holes > blocks_x * blocks_z)
    return Error{fmt("%s: %llu hole blocks; this terrain has only %llu", what.c_str(),
                     static_cast<unsigned long long>(holes),
                     static_cast<unsigned long long>(blocks_x * blocks_z))};
  const std::size_t holes_at = kHeaderBytes + count * kChunkBytes;
  const std::size_t expected = holes_at + holes * kHoleBytes + 8;
  if (in.size() != expected)
    return Error{fmt("%s: %zu bytes; %s (%llu chunks and %llu hole blocks need %zu)", what.c_str(),
                     in.size(), in.size() < expected ? "truncated" : "trailing bytes",
                     static_cast<unsigned long long>(count),
                     static_cast<unsigned long long>(holes), expected)};
  if (fnv1a(in.data(), in.size() - 8) != get<std::uint64_t>(in, in.size() - 8))
    return Error{what + ": checksum mismatch (the file is corrupted)"};
  if ((get<std::uint32_t>(in, 8) == 2 && holes != 0) || get<std::uint64_t>(in, 56) != 0)
    return Error{what +
                 ": reserved header bytes are not zero (written by a newer version, "
                 "or corrupted)"};
  const EditLimits& lim = terrain.edit_limits();
  for (std::uint64_t c = 0; c < count; ++c) {
    const std::size_t at = kHeaderBytes + c * kChunkBytes;
    if (auto s = check_index(in, kHeaderBytes, kChunkBytes, c, chunks_x, chunks_z, "chunk"); !s)
      return Error{s.message()};
    for (std::size_t v = 0; v < kChunkValues; ++v) {
      const auto h = get<float>(in, at + 8 + 4 * v);
      if (!std::isfinite(h) || h < lim.min_height_rel || h > lim.max_height_rel)
        return Error{fmt("%s: chunk %llu holds height %g, outside the edit limits", what.c_str(),
                         static_cast<unsigned long long>(c), double(h))};
    }
  }

  // The hole blocks: inside, ascending, no bit past the terrain's last cell.
  auto mask = std::make_shared<HoleMask>();
  for (std::uint64_t b = 0; b < holes; ++b) {
    const std::size_t at = holes_at + b * kHoleBytes;
    if (auto s = check_index(in, holes_at, kHoleBytes, b, blocks_x, blocks_z, "hole block"); !s)
      return Error{s.message()};
    const auto bx = get<std::uint32_t>(in, at), bz = get<std::uint32_t>(in, at + 4);
    const std::uint64_t k = HoleMask::key(bx, bz);
    const auto bits = get<HoleMask::Bits>(in, at + 8);
    for (std::int64_t c = 0; c < HoleMask::kBlock * HoleMask::kBlock; ++c) {
      const std::int64_t i = (std::int64_t(bx) << HoleMask::kShift) + (c & (HoleMask::kBlock - 1));
      const std::int64_t j = (std::int64_t(bz) << HoleMask::kShift) + (c >> HoleMask::kShift);
      if (((bits[std::size_t(c) >> 6] >> (c & 63)) & 1u) &&
          (i >= std::int64_t(hf.width) - 1 || j >= std::int64_t(hf.height) - 1))
        return Error{fmt("%s: hole block %llu marks cell (%lld, %lld), past the terrain's cells",
                         what.c_str(), static_cast<unsigned long long>(b),
                         static_cast<long long>(i), static_cast<long long>(j))};
    }
    mask->set_block(k, bits);
  }

  // Checked: apply. Undo the current edits, then write the saved chunks. What changed is found
  // by comparing the region the chunks cover (before and after) with what it held.
  EditLayer& layer = terrain.edit_layer();
  const std::uint32_t W = hf.width, H = hf.height;
  std::uint32_t ri0 = ~0u, rj0 = ~0u, ri1 = 0, rj1 = 0;  // chunks touched before or after
  auto cover = [&](std::uint64_t k) {
    const std::uint32_t i0 = std::uint32_t(k) << EditLayer::kChunkShift,
                        j0 = std::uint32_t(k >> 32) << EditLayer::kChunkShift;
    ri0 = std::min(ri0, i0), rj0 = std::min(rj0, j0);
    ri1 = std::max(ri1, std::min(i0 + EditLayer::kChunk - 1, W - 1));
    rj1 = std::max(rj1, std::min(j0 + EditLayer::kChunk - 1, H - 1));
  };
  for (std::uint64_t k : layer.sorted_keys()) cover(k);
  for (std::uint64_t c = 0; c < count; ++c) {
    const std::size_t at = kHeaderBytes + c * kChunkBytes;
    cover(EditLayer::key(get<std::uint32_t>(in, at), get<std::uint32_t>(in, at + 4)));
  }
  auto edit = detail::SurfaceAccess::store(const_cast<Surface&>(terrain.surface())).begin_edit();
  std::vector<float> old;
  const std::size_t rw = ri0 == ~0u ? 0 : std::size_t(ri1 - ri0 + 1);
  if (ri0 != ~0u) {
    old.resize(rw * std::size_t(rj1 - rj0 + 1));
    for (std::uint32_t j = rj0; j <= rj1; ++j)
      for (std::uint32_t i = ri0; i <= ri1; ++i)
        old[(i - ri0) + std::size_t(j - rj0) * rw] = edit->height(i, j);
  }
  layer.restore_all(*edit, W, H);
  for (std::uint64_t c = 0; c < count; ++c) {
    const std::size_t at = kHeaderBytes + c * kChunkBytes;
    const auto cx = get<std::uint32_t>(in, at), cz = get<std::uint32_t>(in, at + 4);
    const std::uint32_t i0 = cx << EditLayer::kChunkShift, j0 = cz << EditLayer::kChunkShift;
    layer.touch(*edit, i0, j0, W, H);
    for (std::uint32_t dj = 0; dj < EditLayer::kChunk && j0 + dj < H; ++dj)
      for (std::uint32_t di = 0; di < EditLayer::kChunk && i0 + di < W; ++di) {
        const float h = get<float>(in, at + 8 + 4 * (di + dj * EditLayer::kChunk));
        if (std::bit_cast<std::uint32_t>(edit->height(i0 + di, j0 + dj)) !=
            std::bit_cast<std::uint32_t>(h))
          edit->write(i0 + di, j0 + dj, h);
      }
  }
  SampleChanges changes;
  for (std::uint32_t j = rj0; ri0 != ~0u && j <= rj1; ++j)
    for (std::uint32_t i = ri0; i <= ri1; ++i) {
      const float before = old[(i - ri0) + std::size_t(j - rj0) * rw], after = edit->height(i, j);
      if (std::bit_cast<std::uint32_t>(before) != std::bit_cast<std::uint32_t>(after))
        changes.add(i, j, before, after);
    }
  edit->commit();
  // The holes: the file's replace the current ones; cells that differ are changes.
  if (const HoleMask* now = detail::SurfaceAccess::holes(terrain.surface())) {
    const std::int64_t last_i = std::int64_t(W) - 2, last_j = std::int64_t(H) - 2;
    now->for_each_in(0, 0, last_i, last_j, [&](std::int64_t i, std::int64_t j) {
      if (!mask->hole(i, j)) changes.add_cell(std::uint32_t(i), std::uint32_t(j));
    });
  }
  mask->for_each_in(0, 0, std::int64_t(W) - 2, std::int64_t(H) - 2,
                    [&](std::int64_t i, std::int64_t j) {
                      if (!terrain.surface().hole(i, j))
                        changes.add_cell(std::uint32_t(i), std::uint32_t(j));
                    });
  detail::SurfaceAccess::publish_holes(const_cast<Surface&>(terrain.surface()), std::move(mask));
  EditResult r;
  terrain.commit(changes, r);
  return r;
}

Result<EditResult> load_edits(Terrain& terrain, EditSource& in) {
  // Read whole (a load is one transaction, checked before anything changes), but never more than
  // one chunk past the largest file this terrain can have: a longer stream is not its edit file.
  const std::size_t cap = max_file_bytes(terrain.info()) + kChunkBytes;
  std::string bytes;
  char buf[1 << 16];
  for (;;) {
    const std::size_t want = std::min(sizeof buf, cap + 1 - bytes.size());
    auto n = in.read(std::span<char>(buf, want));
    if (!n) return n.error();
    if (*n == 0) break;
    bytes.append(buf, std::min(*n, want));
    if (bytes.size() > cap) {
      if (Status why = check_edit_header(terrain, bytes); !why)  // a foreign file says so
        return Error{why.message()};
      return Error{fmt("edit file: larger than any edit file of this terrain (more than %zu "
                       "bytes; at most %zu)",
                       cap, cap - kChunkBytes)};
    }
  }
  return load_edits_from_memory(terrain, bytes);
}

}  // namespace ridgeline
