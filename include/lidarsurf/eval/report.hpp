#pragma once
// Text renderings of an EvaluationResult: a readable table and JSON.
#include <string>

#include "lidarsurf/eval/metrics.hpp"

namespace lidarsurf {

/// Multi-line table: the paper's metrics, then the surface-sampled ones (metres).
std::string format_table(const EvaluationResult& result);

/// JSON object with every field of the result (metres, fractions in [0, 1]).
std::string to_json(const EvaluationResult& result);

}  // namespace lidarsurf
