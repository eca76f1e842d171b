// Private: a Terrain's change log (terrain.h's changes_since): the last kChangeLogCapacity
// changes one by one, and everything older merged into one summary entry. The terrain's own
// record (terrain.cpp makes and copies it); the edit transaction (module/src/edit/) appends to it.
#pragma once

#include <algorithm>
#include <cstdint>
#include <deque>
#include <glm/common.hpp>

#include "ridgeline/log.h"
#include "ridgeline/terrain.h"

namespace ridgeline {

/// The union of two changes: the larger version, the box and the vertex range covering both.
inline TerrainChange merge_changes(const TerrainChange& a, const TerrainChange& b) noexcept {
  TerrainChange m;
  m.version = std::max(a.version, b.version);
  m.box.min = glm::min(a.box.min, b.box.min);
  m.box.max = glm::max(a.box.max, b.box.max);
  m.vertices = {std::min(a.vertices.i0, b.vertices.i0), std::min(a.vertices.j0, b.vertices.j0),
                std::max(a.vertices.i1, b.vertices.i1), std::max(a.vertices.j1, b.vertices.j1)};
  return m;
}

class ChangeLog {
 public:
  /// Appends the change that produced version `c.version` (one more than the last one's); when
  /// the log is full, its oldest entry is merged into the summary.
  void record(const TerrainChange& c) {
    entries_.push_back(c);
    if (entries_.size() > kChangeLogCapacity) {
      summary_ = has_summary_ ? merge_changes(summary_, entries_.front()) : entries_.front();
      has_summary_ = true;
      entries_.pop_front();
    }
  }

  /// Terrain::changes_since() for version < current (`current`: the terrain's version, the
  /// last one recorded).
  TerrainChanges since(std::uint64_t version, std::uint64_t current) const {
    TerrainChanges out;
    out.version = current;
    if (version >= current) return out;
    if (!has_summary_ || version >= summary_.version) {
      // Every change after `version` is held one by one (versions ascend by one).
      RIDGELINE_ASSERT(current - version <= entries_.size());
      const std::size_t first = entries_.size() - std::size_t(current - version);
      out.changes.assign(entries_.begin() + std::ptrdiff_t(first), entries_.end());
      return out;
    }
    // The summary holds changes at or before `version` mixed with later ones: one merged box.
    TerrainChange m = summary_;
    for (const TerrainChange& c : entries_) m = merge_changes(m, c);
    out.trimmed = true;
    out.changes.push_back(m);
    return out;
  }

  std::size_t size() const noexcept { return entries_.size(); }

 private:
  std::deque<TerrainChange> entries_;
  TerrainChange summary_;  // every change dropped from entries_, merged (valid with has_summary_)
  bool has_summary_ = false;
};

}  // namespace ridgeline
