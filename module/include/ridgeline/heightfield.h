// Heightfield: the stored samples of a terrain, validated, placed in the world (docs/surface.md,
// Coordinates).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ridgeline/log.h"
#include "ridgeline/result.h"

namespace ridgeline {

/// Largest |height - height_offset| (metres) a stored sample may have after scaling: 1e5 m, the
/// range edits may produce by default (EditLimits), five times Earth's relief. Heightfield::create
/// refuses a sample beyond it (naming the sample and its value) instead of storing heights near
/// the float limit that no camera, bound or query could use; a no-data value (even -3.4e38, a
/// common GDAL one) is replaced by the fill policy before the check.
inline constexpr double kMaxRelativeHeight = 1e5;

/// HeightfieldDesc::max_samples's default: 16385 x 16385 samples.
inline constexpr std::uint64_t kDefaultMaxSamples = std::uint64_t{16385} * 16385;

/// What to do with samples that are non-finite or equal to the no-data value.
enum class FillPolicy {
  kRefuse,    ///< creation fails, naming the first bad sample (the default)
  kNearest,   ///< replaced by the nearest valid sample (4-neighbour distance, ties by scan order)
  kConstant,  ///< replaced by `fill_constant` (a raw value, scaled like any other)
  /// No ground there: every cell with a missing corner becomes a hole of the terrain made from
  /// the field (Surface::hole, docs/deformation.md, "Holes"); the missing samples themselves
  /// take the nearest valid sample's height as kNearest gives it, so heights and bounds stay
  /// finite (and filling a hole later shows that height).
  kHole,
};

/// Sample spacings a terrain accepts, metres: below a micrometre the lattice's positions vanish
/// next to the origin in the float coordinates views and meshes use; above 1,000 km they no longer
/// describe ground.
inline constexpr double kMinSpacing = 1e-6;
inline constexpr double kMaxSpacing = 1e6;

/// Everything needed to turn raw sample values into a placed heightfield. Defaults are sane.
struct HeightfieldDesc {
  std::uint32_t width = 0;       ///< samples along x (image columns), >= 2
  std::uint32_t height = 0;      ///< samples along z (image rows), >= 2
  double spacing_x = 1.0;        ///< metres between samples along x; kMinSpacing .. kMaxSpacing
  double spacing_z = 1.0;        ///< metres between samples along z; kMinSpacing .. kMaxSpacing
  double origin_x = 0.0;         ///< world x of sample (0, 0), metres; finite
  double origin_z = 0.0;         ///< world z of sample (0, 0), metres; finite
  double height_scale = 1.0;     ///< height = height_offset + height_scale * value; finite, > 0
  double height_offset = 0.0;    ///< metres; finite
  std::optional<double> nodata;  ///< raw value that marks a missing sample
  FillPolicy fill = FillPolicy::kRefuse;
  double fill_constant = 0.0;  ///< raw value used by FillPolicy::kConstant; finite
  /// Refuse sizes above this many samples (checked before allocating). Default 16385 x 16385
  /// (268,468,225: the largest usual 2^k + 1 map that a terrain in memory holds comfortably,
  /// about 1 GiB of float heights); larger worlds are baked (ridgeline/world_file.h) and paged.
  std::uint64_t max_samples = kDefaultMaxSamples;
  /// Name used in error messages (a file name, "default terrain", ...).
  std::string name = "heightfield";
};

/// Checks a descriptor's size, spacing, scale and placement without touching sample data.
/// Loaders call it before allocating. Error messages name `desc.name` and the bad value.
Status validate_heightfield_desc(const HeightfieldDesc& desc);

/// A validated grid of heights. Immutable after creation except through a Terrain's edits
/// (Terrain::apply_edit, which needs exclusive access); move-only; all const methods are safe
/// from any number of threads. Heights are stored as float metres relative to `height_offset()`
/// (so a terrain whose heights sit at 1e6 m keeps float precision); world heights are doubles.
/// Row-major: index = i + j * width.
class Heightfield {
 public:
  /// Validates `desc` and `values` (width * height raw values, row-major) and builds the field.
  /// `materials`, if not empty, holds one material id per cell ((width-1) * (height-1) values) or
  /// per sample (width * height values; cell (i, j) takes sample (i, j)'s id). Fails with a precise
  /// message on any bad input; nothing is built then.
  static Result<Heightfield> create(const HeightfieldDesc& desc, std::span<const float> values,
                                    std::span<const std::uint8_t> materials = {});

  Heightfield(Heightfield&&) noexcept = default;
  Heightfield& operator=(Heightfield&&) noexcept = default;
  Heightfield(const Heightfield&) = delete;
  Heightfield& operator=(const Heightfield&) = delete;

  std::uint32_t width() const noexcept { return width_; }
  std::uint32_t height() const noexcept { return height_; }
  double spacing_x() const noexcept { return spacing_x_; }
  double spacing_z() const noexcept { return spacing_z_; }
  double origin_x() const noexcept { return origin_x_; }
  double origin_z() const noexcept { return origin_z_; }
  double height_offset() const noexcept { return height_offset_; }
  double height_scale() const noexcept { return height_scale_; }
  /// World extent along x and z in metres: (width - 1) * spacing_x, (height - 1) * spacing_z.
  double extent_x() const noexcept { return (width_ - 1) * spacing_x_; }
  double extent_z() const noexcept { return (height_ - 1) * spacing_z_; }

  /// Height of sample (i, j) relative to height_offset(), metres. i < width(), j < height():
  /// asserted (RIDGELINE_ASSERT, log.h: on in Debug and sanitizer builds); no other bounds check,
  /// so a release build reads out of range (this is the queries' inner loop). Use
  /// local_clamped() for indices that may lie outside.
  float local(std::uint32_t i, std::uint32_t j) const noexcept {
    RIDGELINE_ASSERT(i < width_ && j < height_);
    return heights_[i + static_cast<std::size_t>(j) * width_];
  }
  /// Like local() but clamps (i, j) into the grid: the edge-repeating padding of docs/surface.md.
  float local_clamped(std::int64_t i, std::int64_t j) const noexcept;
  /// World height of sample (i, j), metres.
  double world(std::uint32_t i, std::uint32_t j) const noexcept {
    return height_offset_ + local(i, j);
  }
  /// All heights relative to height_offset(), row-major.
  std::span<const float> local_heights() const noexcept { return heights_; }

  /// Lowest and highest height relative to height_offset(); after edits, a range that contains
  /// every height (edits only widen it).
  float min_local() const noexcept { return min_local_; }
  float max_local() const noexcept { return max_local_; }

  bool has_materials() const noexcept { return !materials_.empty(); }
  /// Material id of cell (i, j), 0 when the field has no material layer. i < width-1,
  /// j < height-1: asserted like local().
  std::uint8_t material(std::uint32_t i, std::uint32_t j) const noexcept {
    RIDGELINE_ASSERT(i + 1 < width_ && j + 1 < height_);
    return materials_.empty() ? 0 : materials_[i + static_cast<std::size_t>(j) * (width_ - 1)];
  }

  /// Number of samples replaced by the fill policy at creation.
  std::uint64_t filled_samples() const noexcept { return filled_samples_; }
  /// The cells (index i + j * (width - 1)) that FillPolicy::kHole made holes, ascending; empty
  /// for other policies. A Terrain made from the field starts with these holes.
  std::span<const std::uint64_t> hole_cells() const noexcept { return hole_cells_; }
  /// Bytes held by this object (heights and materials).
  std::size_t memory_bytes() const noexcept {
    return heights_.capacity() * sizeof(float) + materials_.capacity() +
           hole_cells_.capacity() * sizeof(std::uint64_t);
  }
  /// A 64-bit FNV-1a hash of size, placement and height bits: identifies the base data (save files
  /// refuse to load onto another terrain).
  std::uint64_t content_hash() const noexcept;

 private:
  Heightfield() = default;
  friend class EditLayer;  // writes heights during an edit (terrain.h's exclusive access)
  friend class Surface;    // Terrain::clone()
  Heightfield duplicate() const {
    Heightfield h;
    h.heights_ = heights_;
    h.materials_ = materials_;
    h.width_ = width_, h.height_ = height_;
    h.spacing_x_ = spacing_x_, h.spacing_z_ = spacing_z_;
    h.origin_x_ = origin_x_, h.origin_z_ = origin_z_;
    h.height_offset_ = height_offset_, h.height_scale_ = height_scale_;
    h.min_local_ = min_local_, h.max_local_ = max_local_;
    h.filled_samples_ = filled_samples_;
    h.hole_cells_ = hole_cells_;
    return h;
  }

  std::vector<float> heights_;
  std::vector<std::uint8_t> materials_;
  std::uint32_t width_ = 0, height_ = 0;
  double spacing_x_ = 1, spacing_z_ = 1, origin_x_ = 0, origin_z_ = 0;
  double height_offset_ = 0, height_scale_ = 1;
  float min_local_ = 0, max_local_ = 0;
  std::uint64_t filled_samples_ = 0;
  std::vector<std::uint64_t> hole_cells_;
};

/// The built-in default terrain: 1025 x 1025 samples, 2 m spacing (a 2048 m square) at origin
/// (0, 0), seed 1337, fBm value noise with ridges, heights 16.3 .. 218.1 m, with a material map
/// per cell (0 grass; 1 rock on cliffs, slope > 0.8; 2 sand in the lowest 12 % of the height
/// range; 3 snow in the highest 20 %; 4 mud in patches of flat low ground; 5 gravel on slopes
/// 0.55 .. 0.8), from slope, height and noise.
/// Deterministic: the same bytes on every machine. Benchmark figures quoted for the default
/// terrain depend on exactly these parameters.
struct DefaultTerrainParams {
  std::uint32_t size = 1025;
  double spacing = 2.0;
  std::uint32_t seed = 1337;
};
Result<Heightfield> make_default_heightfield(const DefaultTerrainParams& params = {});

}  // namespace ridgeline
