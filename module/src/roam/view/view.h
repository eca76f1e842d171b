// Private: a RoamView's parts. One update (RoamView::update(), roam_view.cpp) runs them in
// order; each file of this folder holds one part:
//
//   diamond_source       where a diamond's sphere and bound are read from (records in resident
//                        pages, detail tiles) and what a split waiting for data requests
//   change_tracker       1. what changed since the last update: edits, pages, detail tiles
//   refiner              the mesh and its changes: split (forced splits), merge, links, entries
//   build_from_roots     the mesh built top down (first update, rebuild, teleport)
//   (roam/front)         2. the front's test: every diamond that may split or merge
//   converge_to_threshold 3a. frame end without a budget: every change the test asks for
//   time_budget          3b. frame end under a time budget: the dual priority queues
//   triangle_cap         3c. frame end under a triangle cap alone: the threshold search
//   output_compaction    4. patches whose buffers outgrew their mesh, renumbered
//   mesh_walk            leaves, hash, invariants, measured error (the view's read-only walks)
#pragma once

#include <memory>
#include <new>

#include "ridgeline/roam_memory.h"
#include "ridgeline/roam_view.h"
#include "roam/view/change_tracker.h"
#include "roam/view/converge_to_threshold.h"
#include "roam/view/diamond_source.h"
#include "roam/view/output_compaction.h"
#include "roam/view/refiner.h"
#include "roam/view/time_budget.h"
#include "roam/view/triangle_cap.h"

namespace ridgeline {

struct RoamView::Impl {
  /// `memory` may be null (the arrays' memory is then the view's own).
  Impl(const Landscape& landscape, std::shared_ptr<RoamMemory> memory);

  /// One update with valid settings and camera (RoamView::update()); throws std::bad_alloc
  /// (roam::OutOfMemory) when an array cannot grow.
  RoamStats update(const RoamSettings& settings, const Camera& camera);
  /// After an array could not grow (in an update or the creation): the mesh back to its roots
  /// and the next update from the roots; returns the error to report.
  Error out_of_memory(const std::bad_alloc& e);

  // First, so that it outlives the arrays whose ranges it takes back.
  std::shared_ptr<RoamMemory> memory;
  roam::DiamondSource source;
  roam::Refiner refiner;
  roam::ChangeTracker changes;
  roam::ConvergeToThreshold converge;
  roam::TimeBudget time_budget;
  roam::TriangleCap triangle_cap;
  roam::OutputCompaction compaction;
  roam::Deadline deadline;
  /// The next update starts from the roots (creation, a mode or metric change, out of memory).
  bool reset_pending = true;
};

}  // namespace ridgeline
