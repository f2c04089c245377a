// Short, human number formatting for the gate's messages and table.
#pragma once

#include <string>

namespace hapticd::gate {

// `v` with `digits` significant digits, no trailing zeros ("1.2", "3200", "4.35e-05", "inf").
std::string format_number(double v, int digits = 4);

}  // namespace hapticd::gate
