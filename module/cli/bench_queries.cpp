// (being written)
#include "bench_queries.h"

namespace ridgeline::cli {
nlohmann::json bench_queries(const Terrain&, const BenchQueriesOptions&) { return {}; }
}  // namespace ridgeline::cli
