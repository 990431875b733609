// Integer point attributes (intensity, class, returns, colour) from values the readers hold as
// doubles (PLY, PCD, text): clamped to the type's range, NaN (no value) as 0. A plain cast of a
// NaN or out-of-range double is undefined behaviour (found by fuzz/text_cloud_fuzz.cpp).
#pragma once

#include <limits>

namespace treelobes {

template <typename T>
T attribute_value(double value) {
    if (!(value > 0.0)) return 0;
    if (value >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
    return static_cast<T>(value);
}

}  // namespace treelobes
