// The streaming picture of docs/detail.md ("Streaming"): a top-down shaded relief around a
// camera of the 100 km world flight (docs/detail.md), where every point
// shows the surface at the finest level whose tile the request rule (detail_stream.h) asks for
// there: fine near the camera, coarser with distance, the stored 32 m surface beyond the
// coarsest radius. Three panels: the stored surface over 200 m around the camera, the streamed
// surface over the same 200 m, and 6 km around the camera. Written as PNG through OpenImageIO.
//   detail_image OUT.png
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "ridgeline/detail_stream.h"
#include "ridgeline/scenes.h"
#include "ridgeline/surface.h"
#include "ridgeline/terrain.h"

using namespace ridgeline;

namespace {

constexpr int kPanel = 512;          // pixels per panel side
constexpr double kExaggeration = 4;  // vertical exaggeration of the shading

// The world of the flight benchmark: the default terrain stretched to 3126 x 3126 samples at
// 32 m, heights x 4 (`--default-size 3126 --spacing 32 --height-scale 4`).
std::shared_ptr<const Terrain> make_world() {
  auto hf = scenes::flight_world();
  if (!hf) return nullptr;
  return Terrain::create(std::move(hf).value()).value();
}

// Height of the level-`level` surface at (x, z) from a resident tile: the piecewise-linear
// interpolation (diagonal rule) of base + detail at the lattice vertices.
double level_height(const Terrain& base, const DetailField& f, const DetailTile& tile, double x,
                    double z) {
  const Heightfield hf = base.surface().to_heightfield().value();
  const std::uint32_t l = tile.key().level;
  const double sx = std::ldexp(hf.spacing_x(), -int(l)), sz = std::ldexp(hf.spacing_z(), -int(l));
  const double u = (x - hf.origin_x()) / sx, v = (z - hf.origin_z()) / sz;
  const std::int64_t i = std::clamp<std::int64_t>(std::int64_t(std::floor(u)), tile.first_i(),
                                                  tile.first_i() + kDetailTileCells - 1);
  const std::int64_t j = std::clamp<std::int64_t>(std::int64_t(std::floor(v)), tile.first_j(),
                                                  tile.first_j() + kDetailTileCells - 1);
  const CellTriangle t = locate_in_cell(i, j, float(std::clamp(u - double(i), 0.0, 1.0)),
                                        float(std::clamp(v - double(j), 0.0, 1.0)));
  double h = 0;
  for (int c = 0; c < 3; ++c) {
    const std::int64_t vi = i + t.di[c], vj = j + t.dj[c];
    const double b = base.height(f.lattice_x(l, vi), f.lattice_z(l, vj)).value_or(0.0);
    h += t.w[c] *
         (b + tile.detail(std::int32_t(vi - tile.first_i()), std::int32_t(vj - tile.first_j())));
  }
  return h;
}

// True when (x, z) lies within half a pixel of an edge of the stored triangles (cell sides and
// the diagonal the rule picks).
bool on_stored_edge(const Heightfield& hf, double x, double z, double px) {
  const double u = (x - hf.origin_x()) / hf.spacing_x(), v = (z - hf.origin_z()) / hf.spacing_z();
  const double fu = u - std::floor(u), fv = v - std::floor(v);
  const double e = 0.5 * px / hf.spacing_x();
  const double diag =
      cell_has_main_diagonal(std::int64_t(std::floor(u)), std::int64_t(std::floor(v)))
          ? std::abs(fu - fv)
          : std::abs(fu + fv - 1);
  return fu < e || fu > 1 - e || fv < e || fv > 1 - e || diag < e;
}

struct Pixel {
  double height = 0;
  std::uint32_t level = 0;
};

// Colours by level (0 = the stored surface).
constexpr float kTint[8][3] = {{0.62f, 0.62f, 0.62f}, {0.35f, 0.45f, 0.85f}, {0.30f, 0.70f, 0.85f},
                               {0.35f, 0.75f, 0.45f}, {0.70f, 0.80f, 0.30f}, {0.95f, 0.75f, 0.30f},
                               {0.95f, 0.50f, 0.30f}, {0.90f, 0.30f, 0.45f}};

// Renders a panel of `width_m` metres centred on the eye into rgb (kPanel x kPanel at column
// offset `x0` of an image `stride` pixels wide).
void render_panel(const Terrain& base, const DetailField& f, const DetailSnapshot& snap,
                  const std::vector<DetailTileNeed>& tiles, const Camera& cam,
                  const DetailViewRule& rule, double width_m, bool stored_only,
                  std::vector<std::uint8_t>& rgb, int stride, int x0) {
  const Heightfield hf = base.surface().to_heightfield().value();
  const double px = width_m / kPanel;
  std::vector<Pixel> img(std::size_t(kPanel) * kPanel);
  auto needed = [&](const DetailTileKey& k) {
    for (const auto& t : tiles)
      if (t.needed && t.key == k) return true;
    return false;
  };
  // Needed tiles by level, looked up per pixel (a few hundred tiles: a linear scan per level
  // would be slow, so cache the last hit per level).
  std::vector<DetailTileKey> last(f.levels() + 1, DetailTileKey{0, 0, 0});
  std::vector<const DetailTile*> last_tile(f.levels() + 1, nullptr);
  for (int r = 0; r < kPanel; ++r)
    for (int c = 0; c < kPanel; ++c) {
      const double x = cam.eye.x + (c + 0.5 - kPanel / 2.0) * px;
      const double z = cam.eye.z + (r + 0.5 - kPanel / 2.0) * px;
      Pixel& p = img[std::size_t(c) + std::size_t(r) * kPanel];
      p.height = base.height(x, z).value_or(0.0);
      for (std::uint32_t l = stored_only ? 0 : f.levels(); l >= 1; --l) {
        const double sx = std::ldexp(hf.spacing_x(), -int(l)) * kDetailTileCells;
        const double sz = std::ldexp(hf.spacing_z(), -int(l)) * kDetailTileCells;
        const DetailTileKey k{l, std::int32_t(std::floor((x - hf.origin_x()) / sx)),
                              std::int32_t(std::floor((z - hf.origin_z()) / sz))};
        if (!(k == last[l])) {
          last[l] = k;
          last_tile[l] = needed(k) ? snap.find(k) : nullptr;
        }
        if (last_tile[l]) {
          p.height = level_height(base, f, *last_tile[l], x, z);
          p.level = l;
          break;
        }
      }
    }
  // Hillshade (light from the north-west, 45 degrees up), tinted by level; rings at R_l.
  const double lx = -0.5, ly = std::sqrt(0.5), lz = -0.5;
  for (int r = 0; r < kPanel; ++r)
    for (int c = 0; c < kPanel; ++c) {
      auto h = [&](int cc, int rr) {
        cc = std::clamp(cc, 0, kPanel - 1);
        rr = std::clamp(rr, 0, kPanel - 1);
        return img[std::size_t(cc) + std::size_t(rr) * kPanel].height * kExaggeration;
      };
      const double gx = (h(c + 1, r) - h(c - 1, r)) / (2 * px);
      const double gz = (h(c, r + 1) - h(c, r - 1)) / (2 * px);
      const double n = std::sqrt(gx * gx + gz * gz + 1);
      const double shade = std::clamp((-gx * lx + ly - gz * lz) / n, 0.0, 1.0);
      const Pixel& p = img[std::size_t(c) + std::size_t(r) * kPanel];
      const double d = std::hypot((c + 0.5 - kPanel / 2.0) * px, (r + 0.5 - kPanel / 2.0) * px);
      bool ring = false;
      for (std::uint32_t l = 1; !stored_only && l <= f.levels(); ++l)
        ring |= std::abs(d - detail_level_radius(f, cam, l, rule)) < 0.6 * px;
      std::uint8_t* out = &rgb[3 * (std::size_t(x0 + c) + std::size_t(r) * std::size_t(stride))];
      for (int ch = 0; ch < 3; ++ch) {
        // The zooms in grey (they compress better), the overview tinted by level.
        const float tint = width_m > 1000 ? kTint[std::min(p.level, 7u)][ch] : 0.8f;
        double v = (0.25 + 0.75 * shade) * (0.45 + 0.55 * tint);
        if (ring) v = 0.08;
        if (stored_only && on_stored_edge(hf, cam.eye.x + (c + 0.5 - kPanel / 2.0) * px,
                                          cam.eye.z + (r + 0.5 - kPanel / 2.0) * px, px))
          v *= 0.6;                                 // the stored triangles
        if (d < 2.5 * px) v = ch == 0 ? 1.0 : 0.0;  // the camera
        // 21 levels per channel: the PNG stays small (docs images <= 300 KB).
        out[ch] = std::uint8_t(std::lround(std::clamp(v, 0.0, 1.0) * 20) * 255 / 20);
      }
    }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: detail_image OUT.png\n");
    return 2;
  }
  // The stored surface, and the same world with the detail streamed over it.
  auto terrain = make_world();
  if (!terrain) return 1;
  DetailParams params;
  params.levels = 7;
  DetailCacheDesc desc;
  desc.worker_threads = 0;
  auto world = scenes::flight_world();
  if (!world) return 1;
  auto detailed = Terrain::create(std::move(world).value(), params, desc);
  if (!detailed) {
    std::fprintf(stderr, "%s\n", detailed.error().message.c_str());
    return 1;
  }
  const DetailField& f = *(*detailed)->surface().detail();
  // The camera: on the flight's line (z = 50 km), over the steepest ground among a few places
  // (where the shape field lets the detail show most), 50 m up, heading east, 1280 x 720
  // pixels, 60 degrees: the benchmark's camera and request rule.
  double best_x = 50000, best_shape = -1;
  for (double x = 20000; x <= 80000; x += 500) {
    const double s = f.shape(0, std::int64_t(x / 32), std::int64_t(50000 / 32));
    if (s > best_shape) best_shape = s, best_x = x;
  }
  Camera cam;
  const double z = 50000;
  cam.eye = {best_x, *terrain->height(best_x, z) + 50, z};
  cam.target = {best_x + 200, cam.eye.y - 30, z};
  DetailViewRule rule;
  DetailCache& cache = *(*detailed)->surface().detail_cache();
  auto stream = DetailStream::create((*detailed)->surface(), cache, rule);
  auto st = stream->frame(cam);
  if (!st || st->needed_resident != st->needed) {
    std::fprintf(stderr, "streaming frame failed\n");
    return 1;
  }
  const auto snap = cache.snapshot();
  // The stored surface and the streamed one over the same 200 m, then 6 km around the camera.
  const int width = 3 * kPanel + 16;
  std::vector<std::uint8_t> rgb(std::size_t(width) * kPanel * 3, 255);
  render_panel(*terrain, f, *snap, stream->tiles(), cam, rule, 200, true, rgb, width, 0);
  render_panel(*terrain, f, *snap, stream->tiles(), cam, rule, 200, false, rgb, width, kPanel + 8);
  render_panel(*terrain, f, *snap, stream->tiles(), cam, rule, 6000, false, rgb, width, 2 * kPanel + 16);

  auto out = OIIO::ImageOutput::create(argv[1]);
  if (!out) {
    std::fprintf(stderr, "%s\n", OIIO::geterror().c_str());
    return 1;
  }
  OIIO::ImageSpec spec(width, kPanel, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("png:compressionLevel", 9);
  if (!out->open(argv[1], spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) ||
      !out->close()) {
    std::fprintf(stderr, "%s: %s\n", argv[1], out->geterror().c_str());
    return 1;
  }
  std::printf("{\"camera\": [%.1f, %.1f, %.1f], \"needed_tiles\": %zu, \"radii_m\": [", cam.eye.x,
              cam.eye.y, cam.eye.z, st->needed);
  for (std::uint32_t l = 1; l <= f.levels(); ++l)
    std::printf("%s%.1f", l > 1 ? ", " : "", detail_level_radius(f, cam, l, rule));
  std::printf("]}\n");
  return 0;
}
