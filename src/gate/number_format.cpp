#include "gate/number_format.h"

#include <cmath>
#include <cstdio>

namespace hapticd::gate {

std::string format_number(double v, int digits) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  if (v == 0.0) return "0";
  char buf[64];
  // Whole numbers a person typed (10000 N/m) read better without an exponent.
  if (std::abs(v) < 1e15 && v == std::round(v)) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
    return buf;
  }
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

}  // namespace hapticd::gate
