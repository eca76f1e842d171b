// The one statistics header of Ridgeline's benchmark programs, tools and sample game: how a
// series of per-frame (or per-repetition) figures becomes the medians, percentiles and maxima
// that the JSON files and docs/ quote. Part of Ridgeline::bench, not of the core library.
//
// THE QUANTILE. quantile(v, q) is the element of 0-based rank floor(q * n) of the n sorted
// values, clamped to the last one: no interpolation, so every figure is a value that was
// measured. q = 0 gives the minimum, q = 1 the maximum, q = 0.5 the median for odd n and the
// upper of the two middle values for even n; the 99th percentile of 360 frames is the 357th
// smallest. Every median and percentile in the project is this one (docs/benchmarks.md, "How to
// read").
#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>
#include <vector>

namespace ridgeline::bench {

/// The q-quantile of `v` (q in [0, 1], clamped), as defined above; NaN when `v` is empty.
double quantile(std::vector<double> v, double q);
/// quantile(v, q), or `empty` when `v` is empty (figures printed as 0 for no frames).
double quantile_or(std::vector<double> v, double q, double empty);
/// quantile(v, 0.5).
double median(std::vector<double> v);
/// Largest element of `v`; NaN when empty.
double max_of(const std::vector<double>& v);
/// Arithmetic mean of `v`; NaN when empty.
double mean(const std::vector<double>& v);
/// `x`, or `fallback` when `x` is NaN (a figure of an empty series).
double or_value(double x, double fallback) noexcept;

/// A JSON number, or null for NaN and infinities (JSON has neither).
nlohmann::ordered_json number(double v);

}  // namespace ridgeline::bench
