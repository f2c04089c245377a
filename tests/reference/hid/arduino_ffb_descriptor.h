// The report descriptor a board built on YukMingLaw/ArduinoJoystickWithFFBLibrary v1.0.0
// (commit ed86e27e) publishes, as its example examples/YourFirstFFBController builds it:
// Joystick_(JOYSTICK_DEFAULT_REPORT_ID, JOYSTICK_TYPE_JOYSTICK, 8 buttons, no hat switch, X and
// Y, Rx and Ry). Two parts, sent back to back by DynamicHID_::getDescriptor:
//   - src/Joystick.cpp, the Joystick_ constructor: Joystick application, a Pointer physical
//     collection holding input report 1 (REPORT_ID written as 0x01 whatever the id passed),
//     8 one-bit buttons, then the axes (16 bit, -32767..32767) in a physical collection of their
//     own, and one End Collection: it closes the Pointer collection, not the application;
//   - src/FFBDescriptor.h, pidReportDescriptor: the PID reports inside that application,
//     ending with the End Collection that closes it. Its ids are shared between kinds (input 1
//     the joystick and output 1 Set Effect, input 2 PID State and output 2 Set Envelope,
//     feature 5 Create New Effect and output 5 Set Constant Force, feature 6 Block Load and
//     output 6 Set Ramp Force, feature 7 PID Pool and output 7 Custom Force Data), and Device
//     Control is a logical collection of usage 0x96 (PID Device Control) with no 0x95 report
//     collection around it, its value an array 1..6 (DC Enable Actuators .. DC Device Continue),
//     as adapt-ffb-joy, whose descriptor it descends from, has it.
// Item by item with the same meaning (HID 1.11 6.2.2), written with the reference devices' own
// item writer (hid_items.h); where the library writes a value in more bytes than it needs
// (0x16 0x00 0x00 for a Logical Minimum of 0) the shortest encoding is used.
#pragma once

#include <cstdint>
#include <vector>

namespace hapticd::reference {

std::vector<std::uint8_t> arduino_ffb_descriptor();

// The report ids of pidReportDescriptor (src/FFBDescriptor.h) and of the joystick's input.
namespace arduino_ffb {
inline constexpr std::uint8_t kJoystickInput = 1, kStateInput = 2;
inline constexpr std::uint8_t kSetEffect = 1, kSetEnvelope = 2, kSetCondition = 3, kSetPeriodic = 4,
                              kSetConstant = 5, kSetRamp = 6, kCustomForceData = 7,
                              kDownloadForceSample = 8, kEffectOperation = 10, kBlockFree = 11,
                              kDeviceControl = 12, kDeviceGain = 13, kSetCustomForce = 14;
inline constexpr std::uint8_t kCreateNewEffect = 5, kBlockLoad = 6, kPidPool = 7;
}  // namespace arduino_ffb

}  // namespace hapticd::reference
