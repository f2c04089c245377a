// device.serial: the shipped examples load as their comments say, and each wrong key is named
// with its line and what is wrong with it.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "config/config_loader.h"
#include "drivers/serial/serial_settings.h"
#include "wiring/registry.h"

namespace hapticd::drivers::serial {
namespace {

config::Config load_example(const std::string& name, const std::vector<std::string>& sets = {}) {
  std::ifstream in(std::string(HAPTICD_SOURCE_DIR) + "/config/" + name);
  std::stringstream s;
  s << in.rdbuf();
  std::vector<config::Override> o;
  for (const auto& set : sets) o.push_back(config::parse_override(set));
  return config::load_config_text(s.str(), name, o, HAPTICD_SOURCE_DIR "/config",
                                  wiring::driver_schemas());
}

std::string errors_of(const std::string& name, const std::vector<std::string>& sets) {
  try {
    load_example(name, sets);
  } catch (const config::ConfigError& e) {
    std::string all;
    for (const auto& m : e.messages()) all += m + "\n";
    return all;
  }
  return "";
}

TEST(SerialConfig, TheExamplesLoadAsTheirCommentsSay) {
  const config::Config haply = load_example("serial-haply-2diy.yaml");
  const SerialSettings& h = serial_settings(haply);
  EXPECT_EQ(h.exchange, Exchange::kRequest);
  ASSERT_EQ(h.startup.size(), 2u);
  EXPECT_EQ(h.startup[1].size(), 26u) << "Device::device_set_parameters for two of each";
  EXPECT_EQ(h.input.positions.size(), 2u);
  EXPECT_TRUE(h.input.positions[1].is_float);
  EXPECT_FALSE(h.input.shape.check);
  EXPECT_EQ(declared_delay_samples(h, 1e-3), 1);
  const config::Config wheel = load_example("serial-stream.yaml");
  const SerialSettings& w = serial_settings(wheel);
  EXPECT_EQ(w.exchange, Exchange::kStream);
  ASSERT_TRUE(w.input.shape.check);
  EXPECT_EQ(w.input.shape.check->algorithm->name, "crc-16/ibm-3740");
  EXPECT_EQ(w.input.shape.check->from, 2u);
  EXPECT_EQ(w.input.fault_mask, 0x02u);
  ASSERT_TRUE(w.output.enable);
  EXPECT_EQ(w.output.enable->field.bits, 1u);
}

TEST(SerialConfig, EachWrongKeyIsNamedWithWhatIsWrong) {
  const std::string wheel = "serial-stream.yaml";
  EXPECT_NE(errors_of(wheel, {"device.serial.baud=12345"})
                .find("device.serial.baud: 12345 is no rate a Linux port takes"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.exchange=poll"}).find("device.serial.exchange"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.input.check.algorithm=crc-32"})
                .find("device.serial.input.check.algorithm"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.input.positions=[{byte: 12, type: i16, scale: 1}]"})
                .find("device.serial.input.positions[0]: byte 12 is also check's"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.input.sync=[0xA5, 0x1FF]"})
                .find("device.serial.input.sync[1]: must be an integer in 0..255"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.output.forces=[{byte: 3, type: i8, scale: 0.001}]"})
                .find("device.serial.output.forces[0]: carries at most 0.127 either way"),
            std::string::npos)
      << errors_of(wheel, {"device.serial.output.forces=[{byte: 3, type: i8, scale: 0.001}]"});
  EXPECT_NE(errors_of(wheel, {"device.serial.output.forces=[{byte: 3, type: i16, endian: big, "
                              "scale: 0.001}, {byte: 5, type: i16, endian: big, scale: 0.001}]"})
                .find("2 field(s) for a mechanism of 1 joint(s)"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.input.positions=[{byte: 3, type: i24, scale: 0}]"})
                .find("device.serial.input.positions[0].scale: must not be 0"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.liveness_ms=1.5"}).find("at least twice latency_ms"),
            std::string::npos);
  EXPECT_NE(errors_of(wheel, {"device.serial.porrt=/dev/ttyACM1"}).find("porrt"),
            std::string::npos);
  const std::string errs = errors_of(wheel, {"device.serial.port="});
  EXPECT_NE(errs.find("device.serial.port"), std::string::npos) << errs;
}

}  // namespace
}  // namespace hapticd::drivers::serial
