// Deformation: brushes, the edit transaction, the sparse edit layer and its file
// (docs/deformation.md).
#include "ridgeline/edit.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>

#include "edit/edit_layer.h"
#include "edit/edit_log.h"
#include "format.h"
#include "surface/ray_hierarchy.h"
#include "ridgeline/detail.h"

namespace ridgeline {

static_assert(std::endian::native == std::endian::little,
              "the edit file is little-endian and read by memcpy");

// ---- brushes ---------------------------------------------------------------------------------

const char* brush_name(Brush b) noexcept {
  switch (b) {
    case Brush::kCrater: return "crater";
    case Brush::kRaise: return "raise";
    case Brush::kLower: return "lower";
    case Brush::kFlatten: return "flatten";
    case Brush::kSmooth: return "smooth";
  }
  return "?";
}

std::optional<Brush> parse_brush(std::string_view name) noexcept {
  for (Brush b : {Brush::kCrater, Brush::kRaise, Brush::kLower, Brush::kFlatten, Brush::kSmooth})
    if (name == brush_name(b)) return b;
  return std::nullopt;
}

Status validate_edit(const Edit& e) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (static_cast<unsigned>(e.brush) > static_cast<unsigned>(Brush::kSmooth))
    return Error{fmt("edit: brush %u; need crater, raise, lower, flatten or smooth",
                     static_cast<unsigned>(e.brush))};
  if (!finite(e.x)) return Error{"edit: x is " + num(e.x) + "; need a finite value"};
  if (!finite(e.z)) return Error{"edit: z is " + num(e.z) + "; need a finite value"};
  if (!finite(e.radius) || !(e.radius > 0))
    return Error{"edit: radius is " + num(e.radius) + "; need a finite value > 0"};
  if (!finite(e.strength) || e.strength < 0 || e.strength > 1)
    return Error{"edit: strength is " + num(e.strength) + "; need a value in 0..1"};
  if (!finite(e.depth) || std::abs(e.depth) > 1e5)
    return Error{"edit: depth is " + num(e.depth) + "; need a finite value within +-1e5 m"};
  if (!finite(e.rim) || e.rim < 0 || e.rim > 1)
    return Error{"edit: rim is " + num(e.rim) + "; need a value in 0..1"};
  if (!finite(e.height)) return Error{"edit: height is " + num(e.height) + "; need a finite value"};
  return {};
}

namespace {

// How far a brush reaches, in radii.
double reach_factor(Brush b) { return b == Brush::kCrater ? 1.5 : 1.0; }

// Smooth falloff (1 - r^2)^2: 1 at the centre, 0 with zero slope at r = 1.
double falloff(double r) {
  const double q = 1.0 - r * r;
  return r < 1.0 ? q * q : 0.0;
}

// The crater profile in units of depth (negative down) at r = distance / radius: a parabolic bowl
// of depth 1 plus a rim of height `rim` peaking at r = 1 and falling smoothly to 0 at r = 1.5.
double crater_profile(double r, double rim) {
  if (r <= 1.0) return (r * r - 1.0) + rim * r * r;
  if (r < 1.5) {
    const double t = (r - 1.0) / 0.5, q = 1.0 - t * t;
    return rim * q * q;
  }
  return 0.0;
}

// Flatten weight: 1 inside half the radius, smoothstep down to 0 at the radius.
double plateau(double r) {
  if (r <= 0.5) return 1.0;
  if (r >= 1.0) return 0.0;
  const double t = (r - 0.5) / 0.5;
  return 1.0 - t * t * (3.0 - 2.0 * t);
}

}  // namespace

// ---- the edit layer --------------------------------------------------------------------------

void EditLayer::touch(const Heightfield& hf, std::uint32_t i, std::uint32_t j) {
  const std::uint64_t k = key(i >> kChunkShift, j >> kChunkShift);
  auto [it, inserted] = originals_.try_emplace(k);
  if (!inserted) return;
  std::vector<float>& o = it->second;
  o.assign(std::size_t{kChunk} * kChunk, 0.0f);
  const std::uint32_t i0 = (i >> kChunkShift) << kChunkShift, j0 = (j >> kChunkShift) << kChunkShift;
  for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < hf.height(); ++dj)
    for (std::uint32_t di = 0; di < kChunk && i0 + di < hf.width(); ++di)
      o[di + dj * kChunk] = hf.local(i0 + di, j0 + dj);
}

std::vector<std::uint64_t> EditLayer::sorted_keys() const {
  std::vector<std::uint64_t> keys;
  keys.reserve(originals_.size());
  for (const auto& kv : originals_) keys.push_back(kv.first);
  std::sort(keys.begin(), keys.end());
  return keys;
}

const std::vector<float>* EditLayer::original(std::uint64_t k) const {
  auto it = originals_.find(k);
  return it == originals_.end() ? nullptr : &it->second;
}

void EditLayer::restore_all(Heightfield& hf) {
  for (const auto& [k, o] : originals_) {
    const std::uint32_t i0 = std::uint32_t(k) << kChunkShift, j0 = std::uint32_t(k >> 32) << kChunkShift;
    for (std::uint32_t dj = 0; dj < kChunk && j0 + dj < hf.height(); ++dj)
      for (std::uint32_t di = 0; di < kChunk && i0 + di < hf.width(); ++di)
        write(hf, i0 + di, j0 + dj, o[di + dj * kChunk]);
  }
  originals_.clear();
}

// ---- the transaction -------------------------------------------------------------------------

namespace {

// Bookkeeping of one transaction: which samples changed, the old/new height range.
struct Changes {
  std::uint32_t i0 = ~0u, j0 = ~0u, i1 = 0, j1 = 0;
  float lo = INFINITY, hi = -INFINITY;
  std::size_t samples = 0;
  void add(std::uint32_t i, std::uint32_t j, float before, float after) {
    i0 = std::min(i0, i), j0 = std::min(j0, j), i1 = std::max(i1, i), j1 = std::max(j1, j);
    lo = std::min({lo, before, after});
    hi = std::max({hi, before, after});
    ++samples;
  }
};

}  // namespace

// What the changed stored samples of `c` changed on `t`'s surface: the cells touching them, the
// surface's height range there before and after, the finest-lattice vertices that moved.
static TerrainChange describe_change(const Terrain& t, const Changes& c) {
  const Heightfield& hf = t.heightfield();
  const int L = int(t.detail_levels());
  // Corners of the cells touching a changed sample (unchanged corners keep their height).
  const std::uint32_t vi0 = c.i0 > 0 ? c.i0 - 1 : 0, vj0 = c.j0 > 0 ? c.j0 - 1 : 0;
  const std::uint32_t vi1 = std::min(c.i1 + 1, hf.width() - 1),
                      vj1 = std::min(c.j1 + 1, hf.height() - 1);
  float lo = c.lo, hi = c.hi;  // the changed samples, before and after
  for (std::uint32_t j = vj0; j <= vj1; ++j)
    for (std::uint32_t i = vi0; i <= vi1; ++i)
      lo = std::min(lo, hf.local(i, j)), hi = std::max(hi, hf.local(i, j));
  // The surface is piecewise linear over those corners, plus detail below the stored resolution.
  const std::int64_t s = std::int64_t{1} << L;
  const double pad = L == 0 ? 0.0
                            : t.detail()->contribution_bound(1, std::uint32_t(L), vi0 * s, vj0 * s,
                                                             vi1 * s, vj1 * s);
  TerrainChange ch;
  ch.box.min = {hf.origin_x() + vi0 * hf.spacing_x(), hf.height_offset() + double(lo) - pad,
                hf.origin_z() + vj0 * hf.spacing_z()};
  ch.box.max = {hf.origin_x() + vi1 * hf.spacing_x(), hf.height_offset() + double(hi) + pad,
                hf.origin_z() + vj1 * hf.spacing_z()};
  if (L == 0) {
    ch.vertices = {c.i0, c.j0, c.i1, c.j1};
  } else {
    // Detail-lattice vertices strictly inside those cells are interpolated from the changed
    // samples; the unchanged corners themselves stay.
    const std::int64_t last_i = t.fine_width() - 1, last_j = t.fine_height() - 1;
    ch.vertices = {std::max<std::int64_t>(0, (std::int64_t(c.i0) - 1) * s + 1),
                   std::max<std::int64_t>(0, (std::int64_t(c.j0) - 1) * s + 1),
                   std::min(last_i, (std::int64_t(c.i1) + 1) * s - 1),
                   std::min(last_j, (std::int64_t(c.j1) + 1) * s - 1)};
  }
  return ch;
}

// After the heights changed: ray pyramid, version, change log and the result's box. Nothing is
// called back: landscapes, views and engines pull the log (Terrain::changes_since).
static void finish_transaction(Terrain& t, const Changes& c, EditResult& r, RayHierarchy& rays,
                               std::uint64_t& version, ChangeLog& log) {
  r.samples_changed = c.samples;
  if (c.samples == 0) return;
  const Heightfield& hf = t.heightfield();
  // Cells touching a changed sample.
  const std::uint32_t ci0 = c.i0 > 0 ? c.i0 - 1 : 0, cj0 = c.j0 > 0 ? c.j0 - 1 : 0;
  const std::uint32_t ci1 = std::min(c.i1, hf.width() - 2), cj1 = std::min(c.j1, hf.height() - 2);
  rays.update_cells(hf, ci0, cj0, ci1, cj1);
  TerrainChange ch = describe_change(t, c);
  ch.version = ++version;
  log.record(ch);
  r.changed = ch.box;
}

TerrainChanges Terrain::changes_since(std::uint64_t version) const {
  if (version <= edit_version_) return log_->since(version, edit_version_);
  // Not a version of this terrain: everything may differ.
  const Heightfield& hf = heightfield_;
  const double pad = detail_ ? detail_->contribution_bound(1) : 0.0;
  TerrainChange whole;
  whole.version = edit_version_;
  whole.box.min = {hf.origin_x(), hf.height_offset() + double(hf.min_local()) - pad, hf.origin_z()};
  whole.box.max = {hf.origin_x() + hf.extent_x(), hf.height_offset() + double(hf.max_local()) + pad,
                   hf.origin_z() + hf.extent_z()};
  whole.vertices = {0, 0, fine_width() - 1, fine_height() - 1};
  TerrainChanges out;
  out.version = edit_version_;
  out.changes.push_back(whole);
  out.trimmed = true;
  return out;
}

Result<EditResult> Terrain::apply_edit(const Edit& e) {
  if (auto s = validate_edit(e); !s) return Error{s.message()};
  Heightfield& hf = heightfield_;
  if (!e.keep_detail && detail_levels_ != 0)
    // Replacing the detail would need deltas on the detail lattice and error bounds (views,
    // rays) that include them; docs/deformation.md, "keep_detail".
    return Error{
        fmt("edit: keep_detail = false is not supported on a terrain with procedural "
            "detail (%u levels): edits are stored at the base spacing (%s m) and the "
            "detail always rides on top of them; use keep_detail = true",
            detail_levels_, num(std::min(hf.spacing_x(), hf.spacing_z())).c_str())};
  const double extent = std::max(hf.extent_x(), hf.extent_z());
  if (e.radius > extent)
    return Error{"edit: radius " + num(e.radius) + " m is larger than the terrain (" +
                 num(extent) + " m)"};
  const EditLimits& lim = edits_->limits;
  EditResult r;
  double radius = e.radius;
  const double area = std::numbers::pi * std::pow(radius * reach_factor(e.brush), 2);
  if (area > lim.max_area_m2) {
    if (lim.refuse_oversize)
      return Error{"edit: the brush covers " + num(area) + " m^2, more than the per-edit cap of " +
                   num(lim.max_area_m2) + " m^2"};
    radius = std::sqrt(lim.max_area_m2 / std::numbers::pi) / reach_factor(e.brush);
    r.clipped = true;
  }
  r.radius_used = radius;
  const double reach = radius * reach_factor(e.brush);
  // Sample range under the brush (lattice units relative to the origin, double: no overflow).
  const double cu = (e.x - hf.origin_x()) / hf.spacing_x(), cv = (e.z - hf.origin_z()) / hf.spacing_z();
  const double ru = reach / hf.spacing_x(), rv = reach / hf.spacing_z();
  const double u0 = std::max(std::ceil(cu - ru), 0.0), u1 = std::min(std::floor(cu + ru), double(hf.width() - 1));
  const double v0 = std::max(std::ceil(cv - rv), 0.0), v1 = std::min(std::floor(cv + rv), double(hf.height() - 1));
  if (!(u0 <= u1 && v0 <= v1)) return r;  // wholly outside: a no-op
  const auto i0 = std::uint32_t(u0), i1 = std::uint32_t(u1), j0 = std::uint32_t(v0), j1 = std::uint32_t(v1);

  // Smooth reads the heights before the edit, one sample around the range.
  std::vector<float> before;
  std::uint32_t bi0 = 0, bj0 = 0, bw = 0, bh = 0;
  if (e.brush == Brush::kSmooth) {
    bi0 = i0 > 0 ? i0 - 1 : 0, bj0 = j0 > 0 ? j0 - 1 : 0;
    bw = std::min(i1 + 1, hf.width() - 1) - bi0 + 1, bh = std::min(j1 + 1, hf.height() - 1) - bj0 + 1;
    before.resize(std::size_t{bw} * bh);
    for (std::uint32_t j = 0; j < bh; ++j)
      for (std::uint32_t i = 0; i < bw; ++i) before[i + j * bw] = hf.local(bi0 + i, bj0 + j);
  }
  const double target = e.height - hf.height_offset();
  const double amount = e.strength * e.depth;
  Changes c;
  for (std::uint32_t j = j0; j <= j1; ++j) {
    const double dz = (double(j) - cv) * hf.spacing_z();
    for (std::uint32_t i = i0; i <= i1; ++i) {
      const double dx = (double(i) - cu) * hf.spacing_x();
      const double r_n = std::sqrt(dx * dx + dz * dz) / radius;
      if (r_n * radius > reach) continue;
      const float old = hf.local(i, j);
      double h = old;
      switch (e.brush) {
        case Brush::kCrater: h += amount * crater_profile(r_n, e.rim); break;
        case Brush::kRaise: h += amount * falloff(r_n); break;
        case Brush::kLower: h -= amount * falloff(r_n); break;
        case Brush::kFlatten: h += e.strength * plateau(r_n) * (target - h); break;
        case Brush::kSmooth: {
          double sum = 0;
          int n = 0;
          for (int b = -1; b <= 1; ++b)
            for (int a = -1; a <= 1; ++a) {
              const std::int64_t x = std::int64_t(i) + a - bi0, z = std::int64_t(j) + b - bj0;
              if (x < 0 || z < 0 || x >= bw || z >= bh) continue;
              sum += before[std::size_t(x) + std::size_t(z) * bw];
              ++n;
            }
          h += e.strength * falloff(r_n) * (sum / n - h);
          break;
        }
      }
      if (h < lim.min_height_rel || h > lim.max_height_rel) {
        h = std::clamp(h, lim.min_height_rel, lim.max_height_rel);
        ++r.samples_clamped;
      }
      const float nh = static_cast<float>(h);
      if (nh == old) continue;
      edits_->touch(hf, i, j);
      EditLayer::write(hf, i, j, nh);
      c.add(i, j, old, nh);
    }
  }
  r.clamped = r.samples_clamped > 0;
  finish_transaction(*this, c, r, *rays_, edit_version_, *log_);
  return r;
}

Status Terrain::set_edit_limits(const EditLimits& l) {
  if (!std::isfinite(l.max_area_m2) || !(l.max_area_m2 > 0))
    return Error{"edit limits: max_area_m2 is " + num(l.max_area_m2) + "; need a finite value > 0"};
  if (!std::isfinite(l.min_height_rel) || !std::isfinite(l.max_height_rel) ||
      !(l.min_height_rel < l.max_height_rel))
    return Error{"edit limits: height range " + num(l.min_height_rel) + " .. " +
                 num(l.max_height_rel) + "; need finite values with min < max"};
  edits_->limits = l;
  return {};
}

const EditLimits& Terrain::edit_limits() const noexcept { return edits_->limits; }

std::size_t Terrain::edited_chunks() const noexcept { return edits_->chunks(); }

std::shared_ptr<Terrain> Terrain::clone() const {
  std::shared_ptr<Terrain> t(new Terrain(heightfield_.duplicate()));
  if (detail_) {
    // The same detail function (the shape field is copied, not re-derived from edited heights),
    // bound to the clone, with a cache of its own.
    auto field = std::shared_ptr<DetailField>(new DetailField(*detail_));
    field->keep_.reset();
    field->base_ = t.get();
    t->detail_ = field;
    DetailCacheDesc desc;
    desc.budget_bytes = std::size_t{64} << 20;
    desc.worker_threads = 0;
    auto cache = DetailCache::create(t->detail_, desc);
    if (cache) t->cache_ = std::move(*cache);
    t->detail_levels_ = t->cache_ ? detail_levels_ : 0;
    t->detail_hash_ = detail_hash_;
  }
  *t->edits_ = *edits_;
  t->base_hash_ = base_hash_;
  t->edit_version_ = edit_version_;
  *t->log_ = *log_;
  return t;
}

// ---- the file --------------------------------------------------------------------------------

namespace {

constexpr char kMagic[8] = {'R', 'I', 'D', 'G', 'E', 'E', 'D', 'T'};
constexpr std::uint32_t kVersion = 1;
constexpr std::size_t kHeaderBytes = 64;
constexpr std::size_t kChunkValues = std::size_t{EditLayer::kChunk} * EditLayer::kChunk;
constexpr std::size_t kChunkBytes = 8 + 4 * kChunkValues;

std::uint64_t fnv1a(const char* p, std::size_t n) {
  std::uint64_t h = 1469598103934665603ull;
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


}  // namespace

Status save_edits(const Terrain& terrain, const std::string& path) {
  const Heightfield& hf = terrain.heightfield();
  const EditLayer& layer = *terrain.edits_;
  const std::vector<std::uint64_t> keys = layer.sorted_keys();
  std::string out;
  out.reserve(kHeaderBytes + keys.size() * kChunkBytes + 8);
  out.append(kMagic, 8);
  put(out, kVersion);
  put(out, EditLayer::kChunk);
  put(out, terrain.base_hash());
  put(out, terrain.detail_hash());
  put(out, hf.width());
  put(out, hf.height());
  put(out, std::uint64_t{keys.size()});
  put(out, std::uint64_t{0});
  put(out, std::uint64_t{0});
  for (std::uint64_t k : keys) {
    const std::uint32_t cx = std::uint32_t(k), cz = std::uint32_t(k >> 32);
    put(out, cx);
    put(out, cz);
    const std::uint32_t i0 = cx << EditLayer::kChunkShift, j0 = cz << EditLayer::kChunkShift;
    for (std::uint32_t dj = 0; dj < EditLayer::kChunk; ++dj)
      for (std::uint32_t di = 0; di < EditLayer::kChunk; ++di) {
        const bool in = i0 + di < hf.width() && j0 + dj < hf.height();
        put(out, in ? hf.local(i0 + di, j0 + dj) : 0.0f);
      }
  }
  put(out, fnv1a(out.data(), out.size()));

  // Temporary file in the same folder, fsync, rename over the target, fsync the folder.
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{"save edits '" + path + "': cannot create '" + tmp + "': " + std::strerror(errno)};
  std::size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::write(fd, out.data() + done, out.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      ::unlink(tmp.c_str());
      return Error{"save edits '" + path + "': writing failed (" + std::strerror(err) +
                   "); the previous file is unchanged"};
    }
    done += std::size_t(n);
  }
  // A full disk may show only here (delayed allocation, network file systems). The descriptor
  // is closed whatever fsync answered.
  int err = ::fsync(fd) != 0 ? errno : 0;
  if (::close(fd) != 0 && err == 0) err = errno;
  if (err != 0) {
    ::unlink(tmp.c_str());
    return Error{"save edits '" + path + "': flushing failed (" + std::strerror(err) +
                 "); the previous file is unchanged"};
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    err = errno;
    ::unlink(tmp.c_str());
    return Error{"save edits '" + path + "': rename failed (" + std::strerror(err) +
                 "); the previous file is unchanged"};
  }
  const std::size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return {};
}

// The header fields that tie a file to a terrain (base hash, detail hash, size); `in` holds at
// least the header.
static Status check_edit_header(const Terrain& terrain, std::string_view in) {
  const Heightfield& hf = terrain.heightfield();
  const std::string what = "edit file";
  if (std::memcmp(in.data(), kMagic, 8) != 0)
    return Error{what + ": not a Ridgeline edit file (bad magic)"};
  const auto version = get<std::uint32_t>(in, 8);
  if (version != kVersion)
    return Error{fmt("%s: version %u; this build reads version %u", what.c_str(), version, kVersion)};
  if (get<std::uint32_t>(in, 12) != EditLayer::kChunk)
    return Error{fmt("%s: chunk size %u; need %u", what.c_str(), get<std::uint32_t>(in, 12),
                     EditLayer::kChunk)};
  if (get<std::uint64_t>(in, 16) != terrain.base_hash())
    return Error{fmt("%s: saved for another terrain (base data hash %016llx, this terrain's is "
                     "%016llx)",
                     what.c_str(), static_cast<unsigned long long>(get<std::uint64_t>(in, 16)),
                     static_cast<unsigned long long>(terrain.base_hash()))};
  if (get<std::uint64_t>(in, 24) != terrain.detail_hash())
    return Error{what + ": saved with other detail parameters (detail hash differs)"};
  if (get<std::uint32_t>(in, 32) != hf.width() || get<std::uint32_t>(in, 36) != hf.height())
    return Error{fmt("%s: saved for a %u x %u terrain; this one is %u x %u", what.c_str(),
                     get<std::uint32_t>(in, 32), get<std::uint32_t>(in, 36), hf.width(), hf.height())};
  return {};
}

Result<EditResult> load_edits_from_memory(Terrain& terrain, std::string_view in) {
  Heightfield& hf = terrain.heightfield_;
  const std::string what = "edit file";
  if (in.size() < kHeaderBytes + 8)
    return Error{fmt("%s: %zu bytes; truncated (a valid file has at least %zu)", what.c_str(),
                     in.size(), kHeaderBytes + 8)};
  if (auto s = check_edit_header(terrain, in); !s) return Error{s.message()};
  const auto count = get<std::uint64_t>(in, 40);
  const std::uint64_t chunks_x = (hf.width() + EditLayer::kChunk - 1) / EditLayer::kChunk;
  const std::uint64_t chunks_z = (hf.height() + EditLayer::kChunk - 1) / EditLayer::kChunk;
  if (count > chunks_x * chunks_z)
    return Error{fmt("%s: %llu chunks; this terrain has only %llu", what.c_str(),
                     static_cast<unsigned long long>(count),
                     static_cast<unsigned long long>(chunks_x * chunks_z))};
  const std::size_t expected = kHeaderBytes + count * kChunkBytes + 8;
  if (in.size() != expected)
    return Error{fmt("%s: %zu bytes; %s (%llu chunks need %zu)", what.c_str(), in.size(),
                     in.size() < expected ? "truncated" : "trailing bytes",
                     static_cast<unsigned long long>(count), expected)};
  if (fnv1a(in.data(), in.size() - 8) != get<std::uint64_t>(in, in.size() - 8))
    return Error{what + ": checksum mismatch (the file is corrupted)"};
  if (get<std::uint64_t>(in, 48) != 0 || get<std::uint64_t>(in, 56) != 0)
    return Error{what +
                 ": reserved header bytes 48..63 are not zero (written by a newer version, "
                 "or corrupted)"};
  const EditLimits& lim = terrain.edits_->limits;
  std::uint64_t prev_key = 0;
  for (std::uint64_t c = 0; c < count; ++c) {
    const std::size_t at = kHeaderBytes + c * kChunkBytes;
    const auto cx = get<std::uint32_t>(in, at), cz = get<std::uint32_t>(in, at + 4);
    if (cx >= chunks_x || cz >= chunks_z)
      return Error{fmt("%s: chunk %llu at (%u, %u) lies outside the terrain", what.c_str(),
                       static_cast<unsigned long long>(c), cx, cz)};
    const std::uint64_t k = EditLayer::key(cx, cz);
    if (c > 0 && k <= prev_key)
      return Error{fmt("%s: chunk %llu out of order or repeated", what.c_str(),
                       static_cast<unsigned long long>(c))};
    prev_key = k;
    for (std::size_t v = 0; v < kChunkValues; ++v) {
      const auto h = get<float>(in, at + 8 + 4 * v);
      if (!std::isfinite(h) || h < lim.min_height_rel || h > lim.max_height_rel)
        return Error{fmt("%s: chunk %llu holds height %g, outside the edit limits", what.c_str(),
                         static_cast<unsigned long long>(c), double(h))};
    }
  }

  // Checked: apply. Undo the current edits, then write the saved chunks.
  EditLayer& layer = *terrain.edits_;
  std::vector<float> old(hf.local_heights().begin(), hf.local_heights().end());
  std::uint32_t ri0 = ~0u, rj0 = ~0u, ri1 = 0, rj1 = 0;  // chunks touched before or after
  auto cover = [&](std::uint64_t k) {
    const std::uint32_t i0 = std::uint32_t(k) << EditLayer::kChunkShift,
                        j0 = std::uint32_t(k >> 32) << EditLayer::kChunkShift;
    ri0 = std::min(ri0, i0), rj0 = std::min(rj0, j0);
    ri1 = std::max(ri1, std::min(i0 + EditLayer::kChunk - 1, hf.width() - 1));
    rj1 = std::max(rj1, std::min(j0 + EditLayer::kChunk - 1, hf.height() - 1));
  };
  for (std::uint64_t k : layer.sorted_keys()) cover(k);
  layer.restore_all(hf);
  for (std::uint64_t c = 0; c < count; ++c) {
    const std::size_t at = kHeaderBytes + c * kChunkBytes;
    const auto cx = get<std::uint32_t>(in, at), cz = get<std::uint32_t>(in, at + 4);
    cover(EditLayer::key(cx, cz));
    const std::uint32_t i0 = cx << EditLayer::kChunkShift, j0 = cz << EditLayer::kChunkShift;
    layer.touch(hf, i0, j0);
    for (std::uint32_t dj = 0; dj < EditLayer::kChunk && j0 + dj < hf.height(); ++dj)
      for (std::uint32_t di = 0; di < EditLayer::kChunk && i0 + di < hf.width(); ++di)
        EditLayer::write(hf, i0 + di, j0 + dj,
                         get<float>(in, at + 8 + 4 * (di + dj * EditLayer::kChunk)));
  }
  Changes changes;
  for (std::uint32_t j = rj0; ri0 != ~0u && j <= rj1; ++j)
    for (std::uint32_t i = ri0; i <= ri1; ++i) {
      const float before = old[i + std::size_t{j} * hf.width()], after = hf.local(i, j);
      if (std::bit_cast<std::uint32_t>(before) != std::bit_cast<std::uint32_t>(after))
        changes.add(i, j, before, after);
    }
  EditResult r;
  finish_transaction(terrain, changes, r, *terrain.rays_, terrain.edit_version_, *terrain.log_);
  return r;
}

Result<EditResult> load_edits(Terrain& terrain, const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Error{"load edits '" + path + "': " + std::strerror(errno)};
  std::string bytes;
  char buf[1 << 16];
  // Cap: the largest valid file for this terrain plus one chunk.
  const Heightfield& hf = terrain.heightfield();
  const std::size_t cap = kHeaderBytes + 8 +
                          (std::size_t((hf.width() + 31) / 32) * ((hf.height() + 31) / 32) + 1) * kChunkBytes;
  for (;;) {
    const std::size_t n = std::fread(buf, 1, sizeof buf, f);
    bytes.append(buf, n);
    if (bytes.size() > cap) {
      std::fclose(f);
      Status why = check_edit_header(terrain, bytes);  // a foreign file says so
      return Error{"load edits '" + path + "': " +
                   (why ? std::string("larger than any edit file of this terrain") : why.message())};
    }
    if (n < sizeof buf) break;
  }
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) return Error{"load edits '" + path + "': read error"};
  auto r = load_edits_from_memory(terrain, bytes);
  if (!r) return Error{"load edits '" + path + "': " + r.error().message};
  return r;
}

}  // namespace ridgeline
