// RoamView: frame-coherent ROAM (Duchaineau et al. 1997) driven by a front that is tested in
// full every update. This file holds the public calls and update(), which runs the view's parts
// (view.h) in order:
//
//   1. pull what changed since the last update (change_tracker): edits, pages, detail tiles;
//      or start from the roots (refiner, build_from_roots)
//   2. test the front: one vectorised pass over every diamond that could split or merge
//      (roam/front; under a time budget in turns: time_budget)
//   3. end the frame in one of three ways, by the settings:
//      - converge to the threshold (converge_to_threshold): every merge the test asks for, then
//        every split, testing each diamond that appears on the way;
//      - under a time budget (time_budget): D97's dual priority queues until the clock stops it;
//      - under a triangle cap alone (triangle_cap): the threshold whose mesh fills the cap
//   4. compact the patch buffers that outgrew their mesh (output_compaction), send the page
//      requests of the splits that wait for data, and count.
//
// With nested bounds and spheres (landscape.h) a diamond's test never passes when a parent's
// fails, so the converged mesh is the unique one the threshold asks for, whatever the camera's
// history: the same as a rebuild from the roots (RoamMode::kRebuild) and, for the same bounds,
// as Lindstrom & Pascucci's stateless SOAR refinement.
#include "ridgeline/roam_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "format.h"
#include "ridgeline/log.h"
#include "roam/view/view.h"
#include "surface/lattice.h"

namespace ridgeline {

using roam::Deadline;
using roam::FrontCamera;

const char* stop_reason_name(StopReason r) noexcept {
  switch (r) {
    case StopReason::kConverged:
      return "converged";
    case StopReason::kTriangleBudget:
      return "triangle_budget";
    case StopReason::kTimeBudget:
      return "time_budget";
  }
  return "converged";
}

float morph_factor(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                   double threshold_px, const Geomorph& g) noexcept {
  if (!(g.window > 0.0) || !(threshold_px > 0.0)) return 1.0f;
  const double dx = double(v.x) - eye.x, dy = double(v.y) - eye.y, dz = double(v.z) - eye.z;
  const double d = std::sqrt(dx * dx + dy * dy + dz * dz) - double(v.morph_radius);
  const double rho = double(v.morph_bound) * projection_scale / (threshold_px * std::max(d, 1e-6));
  return static_cast<float>(std::clamp((rho - 1.0 - g.delay) / g.window, 0.0, 1.0));
}

float morphed_height(const MeshVertex& v, const glm::vec3& eye, double projection_scale,
                     double threshold_px, const Geomorph& g) noexcept {
  return v.y + (1.0f - morph_factor(v, eye, projection_scale, threshold_px, g)) * v.morph_dy;
}

// ---- the update ---------------------------------------------------------------------------------

namespace {

/// How an update's changes end (phase 3), chosen by the settings.
enum class FrameEnd {
  kConverge,         ///< no budget: converged to the threshold (converge_to_threshold.h)
  kPriorityQueues,   ///< a time budget, or a cap the search does not apply to (time_budget.h)
  kThresholdSearch,  ///< a triangle cap alone, screen metric, coherent (triangle_cap.h)
};

FrameEnd frame_end(const RoamSettings& s) {
  const bool cap = s.max_triangles != 0, time = s.budget_ms > 0.0;
  if (cap && !time && s.metric == ErrorMetric::kScreenPixels && s.mode == RoamMode::kCoherent)
    return FrameEnd::kThresholdSearch;
  if (cap || time) return FrameEnd::kPriorityQueues;
  return FrameEnd::kConverge;
}

/// In builds with RIDGELINE_ROAM_PARANOID (the sanitizer stage of scripts/test.sh): the mesh's
/// invariants after each phase, a failure reported through the assertion handler (log.h).
void verify(const roam::Refiner& r, const char* after) {
#ifdef RIDGELINE_ROAM_PARANOID
  if (const std::string e = r.check_invariants(); !e.empty()) {
    const std::string what = std::string("roam view invariants after ") + after + ": " + e;
    detail::assert_failed(what.c_str(), __FILE__, __LINE__);
  }
#else
  (void)r, (void)after;
#endif
}

}  // namespace

RoamView::Impl::Impl(const Landscape& landscape, std::shared_ptr<RoamMemory> memory_in)
    : memory(std::move(memory_in)),
      source(landscape),
      refiner(landscape, source, memory ? &memory->pool() : nullptr) {}

RoamStats RoamView::Impl::update(const RoamSettings& s, const Camera& camera) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point t0 = Clock::now();
  const Landscape& land = refiner.landscape();
  const FrameEnd end = frame_end(s);
  const bool screen = s.metric == ErrorMetric::kScreenPixels;
  const std::uint32_t cap = s.max_triangles;
  RoamStats& stats = refiner.stats();
  stats = RoamStats{};
  refiner.set_worst_failing(0);
  // Under a cap alone, the test starts at the threshold the last update's search ended at.
  const double start_px =
      end == FrameEnd::kThresholdSearch ? triangle_cap.start_threshold(s.threshold) : s.threshold;
  refiner.set_camera(screen ? roam::screen_camera(land, camera, start_px)
                            : FrontCamera::world_metres(s.threshold));
  deadline.start(t0, s.budget_ms);

  // 1. What changed since the last update, or a mesh from the roots: built top down when
  // nothing orders the changes (no time budget, no queues of a cap's first update).
  source.begin_update(!screen);
  const bool build_whole =
      end == FrameEnd::kConverge || (end == FrameEnd::kThresholdSearch && triangle_cap.searching());
  if (reset_pending || s.mode == RoamMode::kRebuild) {
    reset_pending = false;
    changes.mark_synced(land.terrain().edit_version(), land.terrain().surface().hole_cells() > 0);
    refiner.reset_to_roots();
    if (build_whole) refiner.build_from_roots();
  } else {
    changes.pull_edits(refiner);
  }
  changes.pull_tiles(refiner);
  changes.pull_pages(refiner);
  verify(refiner, "the changes were pulled");

  // 2. The front's test: in turns under a time budget (with the changes' priorities for the
  // queues when there is no cap); whole otherwise, with the changes listed. Under a time budget
  // the lists are not needed: collecting them reads every changed entry's record before the
  // first deadline check (0.2-0.4 ms on a 130,000-entry front that the rest of the frame has
  // evicted, most of a 0.5 ms budget).
  if (deadline.has_budget()) {
    time_budget.test_front(refiner, deadline, cap != 0);
  } else {
    refiner.test_front();
    converge.collect(refiner.front());
  }
  // Coherence loses when much of the mesh must go at once (a teleport, a snap turn): a rebuild
  // from the roots then costs less than merging it away first. The merges due tell (each
  // cascades up its ancestors); splits alone never do (a threshold drop keeps the whole mesh).
  // Not under the queues: they keep the mesh and improve it in priority order.
  if (end != FrameEnd::kPriorityQueues && s.mode == RoamMode::kCoherent && !stats.rebuilt &&
      converge.merges_due() > std::max<std::size_t>(512, refiner.front().size() / 8)) {
    refiner.reset_to_roots();
    if (build_whole) refiner.build_from_roots();
    refiner.test_front();
    converge.collect(refiner.front());
  }
  // Under a time budget compaction goes first, in a share of the budget.
  if (deadline.has_budget() && !refiner.output().compact_pending().empty()) {
    const Clock::time_point until = Clock::now() + deadline.share(roam::OutputCompaction::kBudgetShare);
    compaction.run(refiner, &until);
  }

  // 3. The frame's end.
  double reached_px = s.threshold;
  switch (end) {
    case FrameEnd::kConverge:
      converge.run(refiner);
      break;
    case FrameEnd::kPriorityQueues:
      refiner.set_worst_failing(
          time_budget.run(refiner, deadline, s.threshold, cap, converge.scratch()));
      break;
    case FrameEnd::kThresholdSearch:
      reached_px =
          triangle_cap.run(refiner, converge, time_budget, deadline, camera, s.threshold, cap);
      break;
  }
  verify(refiner, "the splits and merges");

  // 4. Output: patches whose buffers hold many more slots than live triangles are compacted;
  // the pages the splits wait for are requested (urgent: loaded by the terrain's workers,
  // resident from a later update on).
  if (!deadline.has_budget()) compaction.run(refiner, nullptr);
  verify(refiner, "compaction");
  stats.requested_pages = source.send_page_requests();

  // Statistics. Unbudgeted, every diamond whose test fails ends unsplit and every other one
  // split (or waiting for data): the largest failing priority seen is the remaining error.
  // Under the queues the splits left in them are added (TimeBudget::run()).
  stats.triangles = refiner.triangles();
  stats.front_size = refiner.front().size();
  const float remaining = refiner.worst_failing();
  stats.max_remaining_error = remaining;
  stats.morph_threshold = end == FrameEnd::kThresholdSearch ? reached_px
                          : stats.stop == StopReason::kTriangleBudget
                              ? std::max(s.threshold, double(remaining))
                              : s.threshold;
  refiner.front().trim();
  refiner.nodes().trim();
  stats.memory_bytes =
      refiner.memory_bytes() + converge.memory_bytes() + time_budget.memory_bytes();
  stats.output_bytes = refiner.output().memory_bytes();
  stats.upload_bytes = refiner.output().take_upload_bytes();
  stats.dirty_patches = refiner.output().dirty_patch_count();
  stats.update_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  return stats;
}

// ---- creation, settings, the calls ---------------------------------------------------------------

// An array could not grow: the update's error, and the view back at its roots (the next update
// rebuilds it). The reset needs no memory beyond what the view holds; should it fail too, the
// next update starts from the roots all the same.
Error RoamView::Impl::out_of_memory(const std::bad_alloc& e) {
  reset_pending = true;
  const std::string why = dynamic_cast<const roam::OutOfMemory*>(&e) != nullptr
                              ? std::string(e.what())
                              : std::string("an allocation failed");
  try {
    refiner.reset_to_roots();
  } catch (const std::bad_alloc&) {
  }
  return Error{"roam view: out of memory: " + why + "; the mesh is back to its root triangles"};
}

Result<std::unique_ptr<RoamView>> RoamView::create(std::shared_ptr<const Landscape> landscape,
                                                   const RoamSettings& settings,
                                                   std::shared_ptr<RoamMemory> memory) {
  if (!landscape) return Error{"roam view: no landscape given"};
  std::unique_ptr<RoamView> v(new RoamView());
  v->landscape_ = std::move(landscape);
  v->impl_ = std::make_unique<Impl>(*v->landscape_, std::move(memory));
  if (auto s = v->set_settings(settings); !s) return Error{s.message()};
  Impl& impl = *v->impl_;
  impl.source.open_pages();
  try {
    impl.refiner.reset_to_roots();
  } catch (const std::bad_alloc& e) {
    return impl.out_of_memory(e);
  }
  impl.changes.mark_synced(v->landscape_->terrain().edit_version(),
                           v->landscape_->terrain().surface().hole_cells() > 0);
  return v;
}

RoamView::~RoamView() = default;

std::uint32_t RoamView::triangle_count() const noexcept {
  return impl_->refiner.triangles();
}

Status RoamView::set_settings(const RoamSettings& s) {
  if (!std::isfinite(s.threshold) || s.threshold < 0.0)
    return Error{
        fmt("roam view: threshold %s; need a finite value >= 0", num(s.threshold).c_str())};
  if (!std::isfinite(s.budget_ms) || s.budget_ms < 0.0)
    return Error{
        fmt("roam view: time budget %s ms; need a finite value >= 0", num(s.budget_ms).c_str())};
  if (s.max_triangles != 0 && s.max_triangles < landscape_->root_count())
    return Error{fmt("roam view: triangle budget %u is below the %u root triangles",
                     s.max_triangles, landscape_->root_count())};
  if (impl_ && (s.mode != settings_.mode || s.metric != settings_.metric))
    impl_->reset_pending = true;
  if (impl_ && s.max_triangles != settings_.max_triangles) impl_->triangle_cap.forget();
  settings_ = s;
  return {};
}

Result<RoamStats> RoamView::update(const Camera& camera) {
  if (settings_.metric == ErrorMetric::kScreenPixels)
    if (auto s = validate_camera(camera); !s) return Error{s.message()};
  try {
    return impl_->update(settings_, camera);
  } catch (const std::bad_alloc& e) {
    return impl_->out_of_memory(e);
  }
}

Result<RoamStats> RoamView::converge(const Camera& camera) {
  const RoamSettings saved = settings_;
  RoamSettings s = settings_;
  s.budget_ms = 0;
  (void)set_settings(s);
  auto r = update(camera);
  // On a paged world, splits that waited for pages go on once the pages are loaded.
  const world::PageStore& store = detail::SurfaceAccess::store(landscape_->terrain().surface());
  for (int round = 0; r && r->requested_pages > 0 && round < 256; ++round) {
    store.wait_idle(60.0);
    auto next = update(camera);
    if (next) next->update_ms += r->update_ms;
    r = next;
  }
  (void)set_settings(saved);
  return r;
}

std::vector<std::uint32_t> RoamView::take_dirty_patches() {
  return impl_->refiner.output().take_dirty();
}

const PatchMesh& RoamView::patch_mesh(std::uint32_t patch) const {
  RIDGELINE_ASSERT(patch < landscape_->patch_count());
  return impl_->refiner.output().mesh(std::min(patch, landscape_->patch_count() - 1));
}

}  // namespace ridgeline
