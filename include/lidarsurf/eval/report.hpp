#pragma once
// Text renderings of an EvaluationResult and of a RingHoldoutResult: a readable table and JSON.
#include <string>

#include "lidarsurf/eval/metrics.hpp"
#include "lidarsurf/eval/ring_holdout.hpp"

namespace lidarsurf {

/// Multi-line table: the paper's metrics, then the surface-sampled ones (metres).
std::string format_table(const EvaluationResult& result);

/// JSON object with every field of the result (metres, fractions in [0, 1]).
std::string to_json(const EvaluationResult& result);

/// One row per range bin and one for all: held-out points, shares within the thresholds (%),
/// mean, median and p90 distance (metres).
std::string format_table(const RingHoldoutResult& result);
std::string to_json(const RingHoldoutResult& result);

}  // namespace lidarsurf
