// The report's scenes (inputs.h).
#include "report/inputs.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>

#include "cli_util.h"
#include "ridgeline/detail.h"
#include "ridgeline/io.h"
#include "ridgeline/log.h"

namespace ridgeline::report {

namespace {
// Loader messages, captured as the user would have seen them.
struct Captured {
  std::vector<std::string> lines;
};
void capture_sink(LogLevel level, std::string_view m, void* user) {
  if (level == LogLevel::kDebug) return;
  const char* tag = level == LogLevel::kInfo      ? "note"
                    : level == LogLevel::kWarning ? "warning"
                                                  : "error";
  static_cast<Captured*>(user)->lines.push_back(std::string(tag) + ": " + std::string(m));
}
Result<std::shared_ptr<const Landscape>> landscape_of(std::shared_ptr<const Terrain> t) {
  return Landscape::create(std::move(t), {.patch_exponent = 6});
}

// Fills a scene from a heightfield load result; a refused load yields a scene without terrain.
Status finish_scene(Scene& sc, Result<Heightfield> hf) {
  if (!hf) {
    sc.messages.push_back("refused: " + hf.error().message);
    return Status{};
  }
  sc.terrain = Terrain::create(std::move(*hf)).value();
  auto l = landscape_of(sc.terrain);
  if (!l) return l.error();
  sc.landscape = *l;
  return Status{};
}

template <class T>
Status write_raw(const std::filesystem::path& p, const std::vector<T>& v) {
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(v.data()), std::streamsize(v.size() * sizeof(T)));
  if (!f) return Error{"cannot write " + p.string()};
  return Status{};
}
void install_stderr_sink() {
  cli::install_log_sink();
}
}  // namespace

Result<Scene> noise_scene(const std::string& png) {
  Scene sc;
  sc.name = "noise1025";
  sc.source = png;
  io::LoadOptions lo;
  lo.placement.spacing_x = lo.placement.spacing_z = 1.0;
  lo.placement.height_scale = scenes::kNoiseHeightScale;
  sc.loader = {{"spacing", {1, 1}}, {"height_scale", scenes::kNoiseHeightScale}};
  Captured cap;
  set_log_sink(capture_sink, &cap);
  auto hf = io::load_heightmap(png, lo);
  install_stderr_sink();
  if (!hf) return hf.error();
  sc.messages = cap.lines;
  if (auto s = finish_scene(sc, std::move(hf)); !s) return Error{s.message()};
  return sc;
}

Result<Scene> dem_scene(const std::string& file, const std::vector<double>& spacing,
                        const std::string& nodata) {
  Scene sc;
  sc.name = "elev_lux";
  sc.source = file;
  io::LoadOptions lo;
  lo.placement.spacing_x = spacing[0];
  lo.placement.spacing_z = spacing[1];
  sc.loader = {{"spacing", spacing},
               {"nodata", nodata.empty() ? "from the file's GDAL_NODATA tag" : nodata},
               {"fill", "nearest"}};
  if (!nodata.empty()) {
    auto nd = cli::parse_finite(nodata, "--dem-nodata");
    if (!nd) return nd.error();
    lo.placement.nodata = *nd;
  }
  Captured cap;
  set_log_sink(capture_sink, &cap);
  // As a user would load it: first plain (the loader takes the no-data value from the file's
  // GDAL_NODATA tag and refuses the missing samples without a fill policy), then with
  // --fill nearest (what the report uses).
  lo.placement.fill = FillPolicy::kRefuse;
  if (auto r = io::load_heightmap(file, lo); !r)
    cap.lines.push_back("without --fill: " + r.error().message);
  else
    cap.lines.push_back("without --fill: loaded, heights " + std::to_string(r->min_local()) +
                        " .. " + std::to_string(r->max_local()) + " m");
  lo.placement.fill = FillPolicy::kNearest;
  auto hf = io::load_heightmap(file, lo);
  install_stderr_sink();
  if (!hf) return hf.error();
  cap.lines.push_back("with --fill nearest: " + std::to_string(hf->filled_samples()) +
                      " samples filled");
  sc.messages = cap.lines;
  if (auto s = finish_scene(sc, std::move(hf)); !s) return Error{s.message()};
  return sc;
}

// Tiles generated asynchronously by one worker thread under the default 256 MiB budget, as in a
// game. The comparators draw from the baked finest lattice (a CDLOD or grid renderer would need
// the detail baked into its height texture: counted in their memory).
Result<Scene> detail_scene(std::uint32_t size, std::uint32_t levels) {
  DefaultTerrainParams dp;
  dp.size = size;
  auto base = make_default_heightfield(dp);
  if (!base) return base.error();
  HeightfieldDesc desc;
  desc.width = base->width();
  desc.height = base->height();
  desc.spacing_x = base->spacing_x();
  desc.spacing_z = base->spacing_z();
  desc.origin_x = base->origin_x();
  desc.origin_z = base->origin_z();
  desc.height_offset = base->height_offset();
  desc.name = "detail";
  std::vector<float> local(base->local_heights().begin(), base->local_heights().end());
  DetailParams params;
  params.levels = levels;
  DetailCacheDesc cache;
  cache.worker_threads = 1;
  auto make = [desc, local, params, cache]()
      -> Result<std::pair<std::shared_ptr<const Terrain>, std::shared_ptr<const Landscape>>> {
    auto hf = Heightfield::create(desc, local);
    if (!hf) return hf.error();
    auto t = Terrain::create(std::move(*hf), params, cache);
    if (!t) return t.error();
    std::shared_ptr<const Terrain> ct = std::move(*t);
    auto l = landscape_of(ct);
    if (!l) return l.error();
    return std::make_pair(ct, *l);
  };
  Scene sc;
  sc.name = "detail" + std::to_string(size);
  sc.source = "default terrain " + std::to_string(size) + " x " + std::to_string(size) +
              " (2 m) with " + std::to_string(levels) + " procedural detail levels";
  auto first = make();
  if (!first) return first.error();
  sc.terrain = first->first;
  sc.landscape = first->second;
  sc.fresh = make;
  const auto t0 = std::chrono::steady_clock::now();
  auto fine = bench::finest_lattice(*sc.terrain);
  if (!fine) return fine.error();
  sc.fine = std::make_shared<const Heightfield>(std::move(*fine));
  sc.detail = {
      {"levels", levels},
      {"seed", params.seed},
      {"amplitude_m", params.amplitude},
      {"gain", params.gain},
      {"finest_spacing_m", {sc.fine->spacing_x(), sc.fine->spacing_z()}},
      {"cache_budget_bytes", cache.budget_bytes},
      {"cache_worker_threads", cache.worker_threads},
      {"field_bytes", sc.terrain->surface().detail()->memory_bytes()},
      {"baked_lattice_bytes", sc.fine->memory_bytes()},
      {"bake_s", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()},
      {"comparators",
       "the uniform grid, CDLOD and SOAR draw from the full-detail surface baked into a "
       "heightfield of the finest lattice (their memory counts it as CDLOD's height texture); "
       "ROAM streams detail tiles from a fresh cold cache in every run"}};
  return sc;
}

Scene synthetic_scene(const std::string& name, std::uint32_t n, scenes::Shape shape, double origin,
                      double spacing) {
  Scene sc;
  sc.name = name;
  sc.source = "synthetic (in memory)";
  (void)finish_scene(sc, scenes::shaped(shape, n, spacing, origin, name));
  return sc;
}

Result<std::vector<Scene>> loader_cases(const std::filesystem::path& dir, std::uint32_t n) {
  std::vector<Scene> out;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  std::vector<float> base(std::size_t(n) * n);
  for (std::uint32_t j = 0; j < n; ++j)
    for (std::uint32_t i = 0; i < n; ++i)
      base[i + std::size_t(j) * n] =
          float(scenes::shape_height(scenes::Shape::kHills, n, int(i), int(j)));
  auto load = [&](const std::string& name, const std::filesystem::path& file, io::RawType type,
                  std::optional<double> scale, bool fill) -> Status {
    Scene sc;
    sc.name = name;
    sc.source = file.filename().string();
    io::LoadOptions lo;
    lo.placement.name = name;
    if (scale) lo.placement.height_scale = *scale;
    if (fill) lo.placement.fill = FillPolicy::kNearest;
    sc.loader = {{"raw", type == io::RawType::kU16 ? "u16" : "f32"},
                 {"size", {n, n}},
                 {"fill", fill ? "nearest" : "refuse"},
                 {"height_scale", lo.placement.height_scale}};
    Captured cap;
    set_log_sink(capture_sink, &cap);
    const io::RawFormat rf{n, n, type};
    auto hf = io::load_raw(file.string(), rf, lo);
    install_stderr_sink();
    sc.messages = cap.lines;
    if (hf)
      sc.messages.push_back("loaded: " + std::to_string(hf->filled_samples()) + " samples filled");
    if (auto s = finish_scene(sc, std::move(hf)); !s) return s;
    out.push_back(std::move(sc));
    return Status{};
  };
  {  // saturated 16-bit: half the samples at 65535, half at 0
    std::vector<std::uint16_t> v(base.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = (k % n) >= n / 2 ? 65535 : 0;
    const auto f = dir / "saturated_u16.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("saturated_u16", f, io::RawType::kU16, 0.01, false); !s)
      return Error{s.message()};
  }
  {  // non-finite floats: NaN, +inf and -inf samples
    std::vector<float> v = base;
    v[n * 3 + 5] = std::nanf("");
    v[n * (n / 2) + n / 2] = std::numeric_limits<float>::infinity();
    v[n * (n - 4) + 7] = -std::numeric_limits<float>::infinity();
    const auto f = dir / "nonfinite_f32.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("nonfinite_f32_refuse", f, io::RawType::kF32, std::nullopt, false); !s)
      return Error{s.message()};
    if (auto s = load("nonfinite_f32_fill_nearest", f, io::RawType::kF32, std::nullopt, true); !s)
      return Error{s.message()};
  }
  {  // saturated floats: +-3e38 (finite, near FLT_MAX)
    std::vector<float> v(base.size());
    for (std::size_t k = 0; k < v.size(); ++k) v[k] = (k % n) >= n / 2 ? 3e38f : -3e38f;
    const auto f = dir / "huge_f32.raw";
    if (auto s = write_raw(f, v); !s) return Error{s.message()};
    if (auto s = load("huge_f32", f, io::RawType::kF32, std::nullopt, false); !s)
      return Error{s.message()};
  }
  return out;
}

}  // namespace ridgeline::report
