// The fuzz targets' oracle primitive. A broken invariant must stop libFuzzer as a crash, with
// the reason on stderr beside the input that caused it, in every build type (assert() would
// vanish under NDEBUG).
#pragma once

#include <string_view>

namespace hapticd::fuzz {

// Prints "fuzz invariant violated: WHAT (DETAIL)" and aborts when ok is false.
void require(bool ok, std::string_view what, std::string_view detail = {});

}  // namespace hapticd::fuzz
