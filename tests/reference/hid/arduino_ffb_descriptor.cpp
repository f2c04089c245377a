// ArduinoJoystickWithFFBLibrary's report descriptor (see arduino_ffb_descriptor.h).
#include "arduino_ffb_descriptor.h"

#include "hid_items.h"

namespace hapticd::reference {
namespace {

using namespace arduino_ffb;

// Every PID report but Device Gain and PID State starts with its Effect Block Index, 1..40.
void block_index(Items& d) { d.use(0x22).logical(1, 40).physical(1, 40).bits(8, 1).out(kVar); }

// The Joystick_ constructor (src/Joystick.cpp) for YourFirstFFBController's arguments.
void joystick(Items& d) {
  d.page(0x01).use(0x04).open(kApplication).use(0x01).id(kJoystickInput).open(kPhysical);
  d.page(0x09).item(0x18, 1).item(0x28, 8).logical(0, 1).bits(1, 8);
  d.item(0x54, 0).item(0x64, 0).in(kVar);  // Unit Exponent 0, Unit none; 8 buttons, no padding
  d.page(0x01).use(0x01).logical(-32767, 32767).bits(16, 4).open(kPhysical);
  for (int u : {0x30, 0x31, 0x33, 0x34}) d.use(u);  // X, Y, Rx, Ry
  d.in(kVar).close();
  d.close();  // "END_COLLECTION": the Pointer collection; the application stays open
}

void state_report(Items& d) {
  d.page(0x0F).use(0x92).open(kLogical).id(kStateInput);
  for (int u : {0x9F, 0xA0, 0xA4, 0xA5, 0xA6}) d.use(u);
  d.logical(0, 1).physical(0, 1).bits(1, 5).in(kVar).item(0x94, 3).in(kConst);
  d.use(0x94).logical(0, 1).physical(0, 1).bits(1, 1).in(kVar);
  d.use(0x22).logical(1, 40).physical(1, 40).bits(7, 1).in(kVar).close();
}

void set_effect(Items& d) {
  d.use(0x21).open(kLogical).id(kSetEffect);
  block_index(d);
  d.use(0x25).open(kLogical);  // Effect Type: twelve usages (ET Custom Force Data twice), 1..12
  for (int u : {0x26, 0x27, 0x30, 0x31, 0x32, 0x33, 0x34, 0x40, 0x41, 0x42, 0x43, 0x28, 0x28})
    d.use(u);
  d.logical(1, 12).physical(1, 12).bits(8, 1).out(kArr).close();
  d.use(0x50).use(0x54).use(0x51).logical(0, 32767).physical(0, 32767);
  d.item(0x64, 0x1003).item(0x54, -3).bits(16, 3).out(kVar).item(0x54, 0).item(0x64, 0);
  d.use(0x52).logical(0, 255).physical(0, 10000).bits(8, 1).out(kVar);
  d.use(0x53).logical(1, 8).physical(1, 8).bits(8, 1).out(kVar);
  d.use(0x55).open(kLogical).page(0x01).use(0x30).use(0x31).logical(0, 1).bits(1, 2).out(kVar);
  d.close();
  d.page(0x0F).use(0x56).item(0x94, 1).out(kVar).item(0x94, 5).out(kConst);
  d.use(0x57).open(kLogical).item(0x08, 0x000A0001).item(0x08, 0x000A0002);
  d.item(0x64, 0x14).item(0x54, -2).logical(0, 255).physical(0, 36000).item(0x64, 0);
  d.bits(8, 2).out(kVar).item(0x54, 0).item(0x64, 0).close();
  d.page(0x0F).use(0x58).open(kLogical).item(0x08, 0x000A0001).item(0x08, 0x000A0002);
  d.item(0x24, 32765).bits(16, 2).out(kVar).close();
  d.close();
}

void envelope_condition(Items& d) {
  d.use(0x5A).open(kLogical).id(kSetEnvelope);
  block_index(d);
  d.use(0x5B).use(0x5D).logical(0, 10000).physical(0, 10000).bits(16, 2).out(kVar);
  d.use(0x5C).use(0x5E).item(0x64, 0x1003).item(0x54, -3).item(0x24, 32767).item(0x44, 32767);
  d.bits(32, 2).out(kVar).item(0x44, 0).item(0x64, 0).item(0x54, 0).close();
  d.use(0x5F).open(kLogical).id(kSetCondition);
  block_index(d);
  d.use(0x23).logical(0, 3).physical(0, 3).bits(4, 1).out(kVar);
  d.use(0x58).open(kLogical).item(0x08, 0x000A0001).item(0x08, 0x000A0002);
  d.bits(2, 2).out(kVar).close();
  d.logical(-10000, 10000).physical(-10000, 10000).use(0x60).bits(16, 1).out(kVar);
  d.physical(-10000, 10000).use(0x61).use(0x62).item(0x94, 2).out(kVar);
  d.logical(0, 10000).physical(0, 10000).use(0x63).use(0x64).bits(16, 2).out(kVar);
  d.use(0x65).item(0x44, 10000).item(0x94, 1).out(kVar).close();
}

void periodic_constant_ramp(Items& d) {
  d.use(0x6E).open(kLogical).id(kSetPeriodic);
  block_index(d);
  d.use(0x70).logical(0, 10000).physical(0, 10000).bits(16, 1).out(kVar);
  d.use(0x6F).logical(-10000, 10000).physical(-10000, 10000).item(0x94, 1).item(0x74, 16);
  d.out(kVar);
  d.use(0x71).item(0x64, 0x14).item(0x54, -2).logical(0, 35999).physical(0, 35999);
  d.bits(16, 1).out(kVar);
  d.use(0x72).logical(0, 32767).physical(0, 32767).item(0x64, 0x1003).item(0x54, -3);
  d.bits(32, 1).out(kVar).item(0x64, 0).item(0x54, 0).close();
  d.use(0x73).open(kLogical).id(kSetConstant);
  block_index(d);
  d.use(0x70).logical(-10000, 10000).physical(-10000, 10000).bits(16, 1).out(kVar).close();
  d.use(0x74).open(kLogical).id(kSetRamp);
  block_index(d);
  d.use(0x75).use(0x76).logical(-10000, 10000).physical(-10000, 10000).bits(16, 2).out(kVar);
  d.close();
}

void custom_force(Items& d) {
  d.use(0x68).open(kLogical).id(kCustomForceData);
  block_index(d);
  d.use(0x6C).logical(0, 10000).physical(0, 10000).bits(16, 1).out(kVar);
  d.use(0x69).logical(-127, 127).physical(0, 255).bits(8, 12).out(0x0102);  // Var, Buffered
  d.close();
  d.use(0x66).open(kLogical).id(kDownloadForceSample).page(0x01).use(0x30).use(0x31);
  d.logical(-127, 127).physical(0, 255).bits(8, 1).out(kVar).close();
}

void operation_free_control_gain(Items& d) {
  d.page(0x0F).use(0x77).open(kLogical).id(kEffectOperation);
  block_index(d);
  d.use(0x78).open(kLogical).use(0x79).use(0x7A).use(0x7B).logical(1, 3).bits(8, 1).out(kArr);
  d.close().use(0x7C).logical(0, 255).physical(0, 255).out(kVar).close();
  d.use(0x90).open(kLogical).id(kBlockFree);
  block_index(d);
  d.close();
  // PIDDeviceControl: the 0x96 collection alone, an array of DC Enable Actuators .. Continue.
  d.use(0x96).open(kLogical).id(kDeviceControl);
  for (int u = 0x97; u <= 0x9C; ++u) d.use(u);
  d.logical(1, 6).bits(8, 1).out(kArr).close();
  d.use(0x7D).open(kLogical).id(kDeviceGain).use(0x7E).logical(0, 255).physical(0, 10000);
  d.bits(8, 1).out(kVar).close();
  d.use(0x6B).open(kLogical).id(kSetCustomForce);
  block_index(d);
  d.use(0x6D).logical(0, 255).physical(0, 255).bits(8, 1).out(kVar);
  d.use(0x51).item(0x64, 0x1003).item(0x54, -3).logical(0, 32767).physical(0, 32767);
  d.bits(16, 1).out(kVar).item(0x54, 0).item(0x64, 0).close();
}

// The feature reports: Create New Effect, PID Block Load (its RAM Pool Available declared as
// an array, FEATURE (Data)), PID Pool.
void feature_reports(Items& d) {
  d.use(0xAB).open(kLogical).id(kCreateNewEffect).use(0x25).open(kLogical);
  for (int u : {0x26, 0x27, 0x30, 0x31, 0x32, 0x33, 0x34, 0x40, 0x41, 0x42, 0x43, 0x28}) d.use(u);
  d.item(0x24, 12).item(0x14, 1).physical(1, 12).bits(8, 1).feature(kArr).close();
  d.page(0x01).use(0x3B).logical(0, 511).physical(0, 511).bits(10, 1).feature(kVar);
  d.item(0x74, 6).feature(0x01).close();
  d.page(0x0F).use(0x89).open(kLogical).id(kBlockLoad);
  d.use(0x22).item(0x24, 40).item(0x14, 1).physical(1, 40).bits(8, 1).feature(kVar);
  d.use(0x8B).open(kLogical).use(0x8C).use(0x8D).use(0x8E);
  d.item(0x24, 3).item(0x14, 1).physical(1, 3).bits(8, 1).feature(kArr).close();
  d.use(0xAC).logical(0, 65535).physical(0, 65535).bits(16, 1).feature(kArr).close();
  d.use(0x7F).open(kLogical).id(kPidPool).use(0x80).bits(16, 1).item(0x14, 0).item(0x34, 0);
  d.item(0x24, 65535).item(0x44, 65535).feature(kVar);
  d.use(0x83).item(0x24, 255).item(0x44, 255).bits(8, 1).feature(kVar);
  d.use(0xA9).use(0xAA).bits(1, 2).logical(0, 1).physical(0, 1).feature(kVar);
  d.bits(6, 1).feature(kConst).close();
}

}  // namespace

std::vector<std::uint8_t> arduino_ffb_descriptor() {
  Items d;
  joystick(d);
  state_report(d);
  set_effect(d);
  envelope_condition(d);
  periodic_constant_ramp(d);
  custom_force(d);
  operation_free_control_gain(d);
  feature_reports(d);
  d.close();  // pidReportDescriptor's last End Collection: the Joystick application
  return d.bytes;
}

}  // namespace hapticd::reference
