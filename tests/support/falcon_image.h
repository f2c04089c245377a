// Firmware images for the simulated Falcon (sim/peers/falcon/), which takes any image of a
// plausible size as Novint's (docs/drivers/falcon.md): hapticd never ships Novint's. Written
// once per test process, under its own name (ctest runs processes side by side); its path is
// what device.falcon.firmware is set to.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <string>
#include <vector>

namespace hapticd::testing {

// An image of `n` bytes (7914: novint_T0.bin's size), the same bytes for every test.
inline std::vector<unsigned char> falcon_image_bytes(std::size_t n = 7914) {
  std::vector<unsigned char> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = static_cast<unsigned char>(i * 7 + 3);
  return v;
}

inline std::string falcon_test_image() {
  static const std::string path = [] {
    const std::string p =
        ::testing::TempDir() + "hapticd-falcon-image-" + std::to_string(::getpid()) + ".bin";
    std::ofstream out(p, std::ios::binary);
    const std::vector<unsigned char> image = falcon_image_bytes();
    out.write(reinterpret_cast<const char*>(image.data()),
              static_cast<std::streamsize>(image.size()));
    return p;
  }();
  return path;
}

}  // namespace hapticd::testing
