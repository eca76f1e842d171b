// The techniques of the frame loop (techniques.h).
#include "ridgeline/bench/techniques.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>

#include "ridgeline/bench/clock.h"
#include "ridgeline/bench/roam_drawn.h"
#include "ridgeline/bench/stats.h"
#include "ridgeline/detail.h"
#include "ridgeline/log.h"

namespace ridgeline::bench {

// ---- ROAM ---------------------------------------------------------------------------------

RoamTechnique::RoamTechnique(std::unique_ptr<RoamView> view, bool converge_first)
    : view_(std::move(view)), converge_first_(converge_first) {
  const Surface& s = view_->landscape().terrain().surface();
  cache_ = s.detail_cache();
  if (cache_ != nullptr) field_bytes_ = double(s.detail()->memory_bytes());
}

std::string RoamTechnique::name() const {
  return view_->settings().mode == RoamMode::kCoherent ? "roam_coherent" : "roam_rebuild";
}

Status RoamTechnique::start(const Camera& first) {
  if (!converge_first_) return {};
  // With a detail cache: converge, wait for the tiles the mesh asked for, repeat.
  for (int round = 0; round < 64; ++round) {
    if (cache_ != nullptr) cache_->update();
    auto s = view_->converge(first);
    if (!s) return s.error();
    if (cache_ == nullptr || s->pending_splits == 0) break;
    (void)cache_->wait_idle(60.0);
  }
  return {};
}

void RoamTechnique::before_update() {
  if (cache_ == nullptr) return;
  // The frame loop's once-per-frame cache update (integrate, evict, publish).
  const auto t0 = Clock::now();
  cache_->update();
  cache_ms_.push_back(ms_since(t0));
}

Status RoamTechnique::update(const Camera& camera) {
  auto s = view_->update(camera);
  if (!s) return s.error();
  last_ = *s;
  time_stops_ += s->stop == StopReason::kTimeBudget;
  rebuilds_ += s->rebuilt;
  compactions_ += s->compacted_patches;
  return {};
}

void RoamTechnique::output() { dirty_ = view_->take_dirty_patches().size(); }

FrameFigures RoamTechnique::figures() const {
  const RoamStats& s = last_;
  FrameFigures f;
  f.triangles = double(s.triangles);
  f.changes = double(s.splits + s.forced_splits + s.merges);
  f.memory_bytes = double(s.memory_bytes);
  f.data_bytes = double(view_->landscape().bound_bytes());
  f.upload_bytes = double(s.upload_bytes);
  f.output_bytes = double(s.output_bytes);
  f.extra = {{"splits", s.splits + s.forced_splits},
             {"forced_splits", s.forced_splits},
             {"merges", s.merges},
             {"priority_updates", s.priority_updates},
             {"front_size", s.front_size},
             {"dirty_patches", dirty_},
             {"compacted_patches", s.compacted_patches},
             {"rebuilt", s.rebuilt},
             {"stopped_by", stop_reason_name(s.stop)},
             {"morph_threshold", s.morph_threshold},
             {"max_remaining_error_px", s.max_remaining_error}};
  if (cache_ != nullptr) {
    const DetailCacheStats cs = cache_->stats();
    f.extra["pending_splits"] = s.pending_splits;
    f.extra["tiles_resident"] = cs.resident_tiles;
    f.extra["detail_bytes"] = double(cs.resident_bytes) + field_bytes_;
    f.extra["tiles_pending"] = cs.pending;
  }
  return f;
}

Drawable RoamTechnique::capture(const MeshErrorMeter& meter) {
  auto snap = std::make_shared<RoamSnapshot>(RoamSnapshot::capture(*view_));
  return [snap, &meter](const Camera& c, bool morph) { return snap->draw(meter, c, morph); };
}

Json RoamTechnique::summary() const {
  Json j = {{"time_budget_stops", time_stops_},
            {"rebuilds", rebuilds_},
            {"compacted_patches", compactions_}};
  if (cache_ != nullptr) {
    const DetailCacheStats cs = cache_->stats();
    j["cache_update_ms_median"] = number(median(cache_ms_));
    j["tiles_generated"] = cs.generated;
    j["tiles_evicted"] = cs.evicted;
    j["tile_generation_s"] = cs.generation_seconds;
    j["worst_tile_lag_frames"] = cs.worst_lag_frames;
  }
  return j;
}

bool RoamTechnique::geomorphs() const {
  const RoamSettings& s = view_->settings();
  return s.metric == ErrorMetric::kScreenPixels && s.threshold > 0;
}

bool RoamTechnique::view_independent() const {
  return view_->settings().metric == ErrorMetric::kWorldMetres;
}

// ---- SOAR ---------------------------------------------------------------------------------

SoarTechnique::SoarTechnique(const Soar& soar, double threshold_px, double path_kappa)
    : soar_(soar), threshold_px_(threshold_px), path_kappa_(path_kappa) {}

double SoarTechnique::kappa_of(const Camera& c) const {
  return std::min(threshold_px_ > 0 ? Soar::kappa_for(c, threshold_px_)
                                    : std::numeric_limits<double>::infinity(),
                  path_kappa_);
}

Status SoarTechnique::update(const Camera& camera) {
  kappa_ = kappa_of(camera);
  last_ = soar_.refine(camera, kappa_, strip_);
  return {};
}

FrameFigures SoarTechnique::figures() const {
  FrameFigures f;
  f.triangles = double(last_.triangles);
  f.memory_bytes = double(soar_.memory_bytes() + strip_.capacity() * sizeof(std::uint32_t));
  f.upload_bytes = double(strip_.size() * sizeof(std::uint32_t));
  f.extra = {{"kappa", number(kappa_)}};
  return f;
}

Drawable SoarTechnique::capture(const MeshErrorMeter&) {
  auto mesh = std::make_shared<const DrawnMesh>(soar_.mesh(strip_));
  return [mesh](const Camera&, bool) { return *mesh; };
}

Json SoarTechnique::diagnose(const Camera& camera) {
  // The same refinement without emitting: what the strip costs is the difference.
  const auto t0 = Clock::now();
  (void)soar_.count(camera, kappa_of(camera));
  const double ms = ms_since(t0);
  refine_only_ms_.push_back(ms);
  return {{"refine_only_ms", ms}};
}

Json SoarTechnique::summary() const {
  return {{"kappa", std::isfinite(path_kappa_) ? number(path_kappa_) : Json("per frame")},
          {"refine_only_ms_median", number(median(refine_only_ms_))},
          {"emitted",
           "one generalised triangle strip of 32-bit vertex indices (the whole mesh, every frame, "
           "inside update_ms; output_ms is 0); vertices static"}};
}

// ---- CDLOD --------------------------------------------------------------------------------

CdlodTechnique::CdlodTechnique(const Cdlod& cdlod, double r0) : cdlod_(&cdlod), r0_(r0) {}

CdlodTechnique::CdlodTechnique(std::unique_ptr<Cdlod> cdlod, double r0)
    : owned_(std::move(cdlod)), cdlod_(owned_.get()), r0_(r0) {}

Status CdlodTechnique::update(const Camera& camera) {
  for (const CellBox& b : pending_) owned_->refresh(b.i0, b.j0, b.i1, b.j1);
  pending_.clear();
  sel_ = cdlod_->select(camera, r0_);
  // Quadrants entering or leaving the selection: CDLOD's "splits + merges".
  std::vector<std::uint64_t> keys;
  for (const auto& c : sel_.chunks)
    for (int q = 0; q < 4; ++q)
      if (c.quadrants >> q & 1)
        keys.push_back(std::uint64_t(c.level) << 58 | std::uint64_t(c.i0) << 30 |
                       std::uint64_t(c.j0) << 2 | std::uint64_t(q));
  std::sort(keys.begin(), keys.end());
  std::vector<std::uint64_t> diff;
  std::set_symmetric_difference(keys.begin(), keys.end(), keys_.begin(), keys_.end(),
                                std::back_inserter(diff));
  keys_ = std::move(keys);
  changes_ = first_ ? 0.0 : double(diff.size());
  first_ = false;
  return {};
}

FrameFigures CdlodTechnique::figures() const {
  FrameFigures f;
  f.triangles = double(sel_.triangles);
  f.changes = changes_;
  f.memory_bytes = double(cdlod_->memory_bytes());
  return f;
}

Drawable CdlodTechnique::capture(const MeshErrorMeter&) {
  return [s = sel_, c = cdlod_](const Camera& cam, bool morph) { return c->mesh(s, cam, morph); };
}

void CdlodTechnique::terrain_changed(const CellBox& box) {
  RIDGELINE_ASSERT(owned_ != nullptr);
  pending_.push_back(box);
}

// ---- uniform grid -------------------------------------------------------------------------

GridTechnique::GridTechnique(const Grid& grid, double target)
    : grid_(grid), g_(UniformGrid::for_triangles(grid, target)), vertices_(g_.vertices(grid)) {}

Status GridTechnique::update(const Camera&) {
  for (const CellBox& b : pending_)
    resampled_ += g_.resample(grid_, vertices_, double(b.i0), double(b.j0), double(b.i1),
                              double(b.j1));
  pending_.clear();
  return {};
}

FrameFigures GridTechnique::figures() const {
  FrameFigures f;
  f.triangles = double(g_.triangles());
  f.changes = 0;
  f.memory_bytes = double(g_.memory_bytes());
  f.upload_bytes = 0;
  return f;
}

Drawable GridTechnique::capture(const MeshErrorMeter&) {
  auto mesh = std::make_shared<const DrawnMesh>(g_.mesh_of(vertices_));
  return [mesh](const Camera&, bool) { return *mesh; };
}

Json GridTechnique::summary() const {
  Json j = {{"grid_quads", {g_.nx, g_.nz}}};
  if (changed_ever_) j["vertices_resampled"] = resampled_;
  return j;
}

void GridTechnique::terrain_changed(const CellBox& box) {
  pending_.push_back(box);
  changed_ever_ = true;
}

}  // namespace ridgeline::bench
