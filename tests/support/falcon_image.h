// A firmware image for the simulated Falcon (sim/peers/falcon/), which takes any image of a
// plausible size as Novint's (docs/drivers/falcon.md): hapticd never ships Novint's. Written
// once per test process, under its own name (ctest runs processes side by side); its path is
// what device.falcon.firmware is set to.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>

namespace hapticd::testing {

inline std::string falcon_test_image() {
  static const std::string path = [] {
    const std::string p =
        ::testing::TempDir() + "hapticd-falcon-image-" + std::to_string(::getpid()) + ".bin";
    std::ofstream out(p, std::ios::binary);
    for (int i = 0; i < 7914; ++i) out.put(static_cast<char>(i * 31 + 7));
    return p;
  }();
  return path;
}

}  // namespace hapticd::testing
