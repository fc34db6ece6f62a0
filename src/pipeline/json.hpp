#pragma once
// The pipeline's JSON writing (summary.json, rgbl eval's report): nlohmann's ordered_json keeps the
// keys in the order written, for people reading the file.

#include <nlohmann/json.hpp>

#include <cmath>

namespace rgbl::detail {

using Json = nlohmann::ordered_json;

// NaN and infinities are not JSON: null.
inline Json json_number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

}  // namespace rgbl::detail
