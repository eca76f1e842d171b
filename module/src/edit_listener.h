// Private: how a Terrain tells the Landscapes built on it, and a Landscape its RoamViews, that an
// edit changed some samples (terrain.h's apply_edit, edit.cpp).
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include "ridgeline/edit.h"

namespace ridgeline::detail {

/// The samples an edit changed: the inclusive index rectangle [i0, i1] x [j0, j1] holding every
/// changed sample (some samples inside it may be unchanged).
struct EditRegion {
  std::uint32_t i0 = 0, j0 = 0, i1 = 0, j1 = 0;
};

/// Registered with Terrain::add_listener (a Landscape) or Landscape::add_listener (a RoamView).
/// Called inside the edit transaction, with exclusive access; adds its work counts to `result`.
class EditListener {
 public:
  virtual void on_edit(const EditRegion& region, EditResult& result) = 0;

 protected:
  ~EditListener() = default;
};

}  // namespace ridgeline::detail

namespace ridgeline {

/// A Terrain's registered landscapes (guarded: landscapes may be created on several threads).
struct Terrain::Listeners {
  std::mutex mutex;
  std::vector<detail::EditListener*> list;
};

}  // namespace ridgeline
