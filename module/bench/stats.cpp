// Statistics of benchmark series (ridgeline/bench/stats.h: the quantile's definition).
#include "ridgeline/bench/stats.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ridgeline::bench {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return kNaN;
  const double qc = std::clamp(std::isnan(q) ? 0.0 : q, 0.0, 1.0);
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(qc * double(v.size())));
  std::nth_element(v.begin(), v.begin() + std::ptrdiff_t(k), v.end());
  return v[k];
}

double quantile_or(std::vector<double> v, double q, double empty) {
  return v.empty() ? empty : quantile(std::move(v), q);
}

double median(std::vector<double> v) { return quantile(std::move(v), 0.5); }

double max_of(const std::vector<double>& v) {
  return v.empty() ? kNaN : *std::max_element(v.begin(), v.end());
}

double mean(const std::vector<double>& v) {
  return v.empty() ? kNaN : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}

double or_value(double x, double fallback) noexcept { return std::isnan(x) ? fallback : x; }

nlohmann::ordered_json number(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

}  // namespace ridgeline::bench
