// Synthetic scenes shared by the tests, the benchmarks (`ridge bench`, `ridge report`) and the
// sample game: one definition of each test field and camera path, so that a figure measured in
// one place is measured on the same data everywhere.
//
// Ridgeline::scenes is not part of the installed library: it is the project's fixture code. It
// depends on Ridgeline::terrain only (no image libraries). Every function is pure (no state) and
// safe to call from any thread.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ridgeline/camera.h"
#include "ridgeline/heightfield.h"
#include "ridgeline/result.h"

namespace ridgeline::scenes {

/// Size and placement of a synthetic field (the HeightfieldDesc fields a scene chooses).
struct FieldDesc {
  std::uint32_t width = 65, height = 65;  ///< samples, >= 2 each
  double spacing_x = 1, spacing_z = 1;    ///< metres between samples, > 0
  double origin_x = 0, origin_z = 0;      ///< world position of sample (0, 0), metres
  double height_offset = 0;               ///< added to every height, metres
  std::string name = "synthetic";
};

/// A field whose sample (i, j) has height `height(i, j)` metres above the offset. `materials`,
/// when not empty, as Heightfield::create takes them. Fails as Heightfield::create does (a bad
/// size or spacing, a non-finite height), naming the value.
Result<Heightfield> field(const FieldDesc& desc, const std::function<double(int i, int j)>& height,
                          const std::vector<std::uint8_t>& materials = {});

/// The report's synthetic shapes on an n x n field with coordinates x, z in [0, 1]:
enum class Shape {
  kHills,  ///< 60 sin(6.1x) cos(4.3z) + 25 sin(23x + 17z) + 8 sin(71x) sin(53z) + 100 m
  kCliff,  ///< a 1,000 m step at i >= n / 2, plus 5 % of kHills
  kFlat,   ///< 0 m everywhere
};
/// Height of `shape` at sample (i, j) of an n x n field.
double shape_height(Shape shape, std::uint32_t n, int i, int j);
/// An n x n field of `shape` (n >= 2) at `spacing` metres, its origin at (origin, origin).
Result<Heightfield> shaped(Shape shape, std::uint32_t n, double spacing, double origin = 0,
                           const std::string& name = "synthetic");

/// The world of the detail flight benchmark (`ridge bench detail --default-terrain --default-size
/// 3126 --spacing 32 --height-scale 4`): the built-in default terrain at 3126 x 3126 samples,
/// 32 m apart (100 km square), heights x 4, with its materials.
Result<Heightfield> flight_world();

// ---- the peers' noise field and circle path ------------------------------------------------
// The inputs other terrain systems were measured on (figures quoted in docs/benchmarks.md): a
// 1025 x 1025 value-noise field of 8 octaves (frequency 1/256 per sample doubling per octave,
// amplitude 160 m halving), stored as 16-bit values of 5 mm (heights 30.9 .. 295.4 m at spacing
// 1 m), and a 360-frame circular flyover over it.

inline constexpr std::uint32_t kNoiseSize = 1025;
inline constexpr double kNoiseHeightScale = 0.005;  ///< metres per stored value

/// Octave value noise at sample (x, y), metres, before quantisation.
double noise_height(int x, int y);
/// The stored values, row-major (index x + y * 1025): round(noise_height / 0.005), ties to even.
std::vector<std::uint16_t> noise_samples();
/// The field as loaded with `--spacing 1 --height-scale 0.005`: heights 0.005 * value metres.
Result<Heightfield> noise_field();
/// The 360-frame circle: radius 300 m around (512, 512) at 1 degree per frame, 25 m above the
/// highest stored height, looking along the circle and 0.35 rad down; 90 degrees, 1024 x 1024.
std::vector<Camera> noise_circle();

// ---- generated worlds for the world benchmark ---------------------------------------------------
// Value-noise fBm whose features are set in samples, not stretched to the size: 12 octaves of
// wavelength 8,192 samples down to 4 (amplitude 550 m halving, then 0.55 per octave), plus a
// ridged octave at 1,024: any size shows the same kind of ground everywhere, as a real DEM does.
// Stored as 16-bit values of 2 cm (heights 0 .. 1,310 m).

inline constexpr double kWorldHeightScale = 0.02;  ///< metres per stored value

/// Rows [j0, j1) of a generated world `width` samples wide: row-major 16-bit values into `out`
/// ((j1 - j0) * width of them). Deterministic (integer hashing, float arithmetic in a fixed
/// order): the same values on every machine, whatever rows a call covers.
void generated_world_rows(std::uint32_t width, std::uint32_t j0, std::uint32_t j1,
                          std::uint32_t seed, std::uint16_t* out);

}  // namespace ridgeline::scenes
