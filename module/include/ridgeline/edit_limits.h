// Limits that give every edit a defined answer (docs/deformation.md, "Limits"): plain data a
// Terrain holds (Terrain::set_edit_limits) and every edit and edit load obeys. Part of the edit
// API (edit.h); a header of its own so that terrain.h holds them without the brushes.
#pragma once

namespace ridgeline {

/// Limits that give every edit a defined answer. Plain data; Terrain::set_edit_limits().
struct EditLimits {
  /// Largest area one edit may cover, square metres (pi x reach^2, reach being the brush's outer
  /// radius). A larger edit is clipped to this area (its radius shrunk, EditResult::clipped) or,
  /// with refuse_oversize, refused. Default 1e6 m^2 (a crater of ~560 m reach).
  double max_area_m2 = 1e6;
  bool refuse_oversize = false;
  /// World heights an edit may produce; samples driven past them are clamped and the result says
  /// so (EditResult::clamped). Defaults: -1e5 .. 1e5 m relative to the heightfield's offset.
  double min_height_rel = -1e5, max_height_rel = 1e5;
};

}  // namespace ridgeline
