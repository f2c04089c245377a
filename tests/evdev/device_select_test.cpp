// `hapticd devices` for evdev: the select: line it prints is what a user pastes into the
// configuration, so it must parse back and select that device, whatever the device calls
// itself (a USB device names itself: quotes, backslashes and control bytes included).
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "drivers/evdev/device_select.h"

namespace hapticd::drivers::evdev {
namespace {

InputListing wheel(std::string name, std::string uniq, std::string path) {
  InputListing d;
  d.path = std::move(path);
  d.name = std::move(name);
  d.uniq = std::move(uniq);
  d.vendor_id = 0x046d;
  d.product_id = 0xc293;
  d.ff_constant = true;
  return d;
}

// The mapping after "select: " on the listing's line for `path`.
YAML::Node select_line(const std::string& listing, const std::string& path) {
  const std::size_t at = listing.find("  " + path + "  ");
  EXPECT_NE(at, std::string::npos) << listing;
  const std::size_t key = listing.find("select: ", at);
  const std::size_t end = listing.find('\n', key);
  return YAML::Load(listing.substr(key + 8, end - key - 8));
}

Selector from(const YAML::Node& n) {
  Selector s;
  if (n["name"]) s.name = n["name"].as<std::string>();
  if (n["uniq"]) s.uniq = n["uniq"].as<std::string>();
  if (n["path"]) s.path = n["path"].as<std::string>();
  if (n["vendor_id"]) s.vendor_id = static_cast<std::uint16_t>(n["vendor_id"].as<unsigned>());
  if (n["product_id"]) s.product_id = static_cast<std::uint16_t>(n["product_id"].as<unsigned>());
  return s;
}

TEST(EvdevDeviceSelect, ASelectLinePastesBackAsTheDeviceItListsWhateverItsName) {
  const std::string hostile = "Wheel \"Pro\" \\ 2\x1b[2J";
  const std::vector<InputListing> all = {wheel(hostile, "", "/dev/input/event3"),
                                         wheel("Other", "", "/dev/input/event4")};
  const std::string listing = format_listing(all, 0);
  EXPECT_EQ(listing.find('\x1b'), std::string::npos) << "a control byte reached the terminal";
  const YAML::Node n = select_line(listing, "/dev/input/event3");
  EXPECT_EQ(n["name"].as<std::string>(), hostile);
  const Selection picked = select_one(from(n), "", all);
  ASSERT_TRUE(picked.device.has_value()) << picked.error;
  EXPECT_EQ(picked.device->path, "/dev/input/event3");
}

TEST(EvdevDeviceSelect, TwinsAreToldApartByTheirSerialOrElseByTheirNode) {
  const std::vector<InputListing> all = {
      wheel("Wheel", "A1", "/dev/input/event3"), wheel("Wheel", "B2", "/dev/input/event4"),
      wheel("Wheel", "", "/dev/input/event5"), wheel("Wheel", "", "/dev/input/event6")};
  const std::string listing = format_listing(all, 0);
  for (const InputListing& d : all) {
    const YAML::Node n = select_line(listing, d.path);
    const Selection picked = select_one(from(n), d.path, all);
    ASSERT_TRUE(picked.device.has_value()) << d.path << ": " << picked.error;
    EXPECT_EQ(picked.device->path, d.path);
  }
  EXPECT_EQ(select_line(listing, "/dev/input/event3")["uniq"].as<std::string>(), "A1");
  EXPECT_EQ(select_line(listing, "/dev/input/event5")["path"].as<std::string>(),
            "/dev/input/event5");
}

}  // namespace
}  // namespace hapticd::drivers::evdev
