// The pure CAN codecs: CiA 301 (NMT, SYNC, heartbeat, EMCY, expedited SDO, the PDOs), the CiA
// 402 power state machine from both ends, ODrive CAN Simple for 0.5 and 0.6, and the bus-load
// arithmetic. Malformed input decodes to a named problem, never to a crash.
#include <gtest/gtest.h>

#include "drivers/can/can_bus_load.h"
#include "drivers/can/canopen.h"
#include "drivers/can/cia402.h"
#include "drivers/can/odrive_protocol.h"

namespace hapticd::drivers::can {
namespace {

using canopen::SdoAddress;
using canopen::SdoReply;
using cia402::PowerState;

TEST(CanOpen, ExpeditedSdoDownloadCarriesSizeIndexAndValue) {
  const CanFrame f = canopen::sdo_download_request(3, {0x6060, 0}, 10, 1);
  EXPECT_EQ(f.id, 0x603u);
  ASSERT_EQ(f.len, 8);
  EXPECT_EQ(f.data[0], 0x2F);  // download, expedited, 1 byte
  EXPECT_EQ(f.data[1], 0x60);
  EXPECT_EQ(f.data[2], 0x60);
  EXPECT_EQ(f.data[3], 0x00);
  EXPECT_EQ(f.data[4], 10);
  EXPECT_EQ(canopen::sdo_download_request(3, {0x1006, 0}, 1000, 4).data[0], 0x23);
  EXPECT_EQ(canopen::sdo_download_request(3, {0x6040, 0}, 0x0F, 2).data[0], 0x2B);
  // The server reads back what the client wrote.
  const canopen::SdoRequest r =
      canopen::decode_sdo_request(canopen::sdo_download_request(3, {0x1017, 0}, 0x12345678, 2));
  EXPECT_EQ(r.kind, canopen::SdoRequest::Kind::kDownload);
  EXPECT_EQ(r.size, 2);
  EXPECT_EQ(r.value, 0x5678u) << "a 2-byte write keeps 2 bytes";
}

TEST(CanOpen, SdoRepliesDecodeValuesConfirmationsAndAborts) {
  const SdoAddress rated{0x6076, 0};
  const SdoReply up = canopen::decode_sdo_reply(canopen::sdo_upload_reply(1, rated, 500, 4), rated);
  EXPECT_EQ(up.kind, SdoReply::Kind::kUploadValue);
  EXPECT_EQ(up.value, 500u);
  const SdoReply two =
      canopen::decode_sdo_reply(canopen::sdo_upload_reply(1, rated, 0xABCD1234, 2), rated);
  EXPECT_EQ(two.size, 2);
  EXPECT_EQ(two.value, 0x1234u);
  EXPECT_EQ(canopen::decode_sdo_reply(canopen::sdo_download_confirm(1, rated), rated).kind,
            SdoReply::Kind::kDownloadConfirmed);
  const SdoReply abort = canopen::decode_sdo_reply(
      canopen::sdo_abort_frame(1, canopen::kSdoTxBase, rated, 0x06020000), rated);
  EXPECT_EQ(abort.kind, SdoReply::Kind::kAbort);
  EXPECT_EQ(abort.abort_code, 0x06020000u);
  EXPECT_EQ(canopen::describe_sdo_abort(0x06020000),
            "object does not exist in the object dictionary");
  EXPECT_EQ(canopen::describe_sdo_abort(0x06090030), "invalid value for parameter");
  EXPECT_NE(canopen::describe_sdo_abort(0x12345678).find("does not define"), std::string::npos);
  // A reply about another object is not the answer; a short one is malformed, with a reason.
  EXPECT_EQ(canopen::decode_sdo_reply(canopen::sdo_download_confirm(1, {0x6071, 0}), rated).kind,
            SdoReply::Kind::kOtherObject);
  CanFrame shortened = canopen::sdo_download_confirm(1, rated);
  shortened.len = 5;
  const SdoReply bad = canopen::decode_sdo_reply(shortened, rated);
  EXPECT_EQ(bad.kind, SdoReply::Kind::kMalformed);
  EXPECT_STRNE(bad.problem, "");
  CanFrame segmented = canopen::sdo_download_confirm(1, rated);
  segmented.data[0] = 0x41;  // segmented upload initiate
  EXPECT_EQ(canopen::decode_sdo_reply(segmented, rated).kind, SdoReply::Kind::kMalformed);
}

TEST(CanOpen, EmcyDecodesCodeAndRegisterAndNamesTheClass) {
  const auto e = canopen::decode_emcy(canopen::emcy_frame(2, 0x2310, 0x03));
  ASSERT_TRUE(e);
  EXPECT_EQ(e->code, 0x2310);
  EXPECT_EQ(e->error_register, 0x03);
  EXPECT_EQ(canopen::describe_emcy_code(0x2310),
            "0x2310 continuous over-current (device output side)");
  EXPECT_EQ(canopen::describe_emcy_code(0x3299), "0x3299 voltage inside the device");
  EXPECT_EQ(canopen::describe_emcy_code(0x5123), "0x5123 device hardware");
  EXPECT_EQ(canopen::describe_emcy_code(0x8130), "0x8130 life guard or heartbeat error");
  CanFrame truncated = canopen::emcy_frame(2, 0x2310, 0x03);
  truncated.len = 2;
  EXPECT_FALSE(canopen::decode_emcy(truncated)) << "a truncated EMCY is not decoded as one";
}

TEST(CanOpen, HeartbeatNmtSyncAndPdos) {
  EXPECT_EQ(canopen::decode_heartbeat(canopen::heartbeat_frame(5, canopen::NmtState::kOperational)),
            canopen::NmtState::kOperational);
  CanFrame hb = canopen::heartbeat_frame(5, canopen::NmtState::kOperational);
  hb.data[0] = 0x33;
  EXPECT_FALSE(canopen::decode_heartbeat(hb)) << "no such NMT state";
  hb.len = 2;
  EXPECT_FALSE(canopen::decode_heartbeat(hb));
  const CanFrame nmt = canopen::nmt_command(canopen::NmtCommand::kStart, 5);
  EXPECT_EQ(canopen::decode_nmt(nmt, 5), canopen::NmtCommand::kStart);
  EXPECT_FALSE(canopen::decode_nmt(nmt, 6)) << "addressed to another node";
  EXPECT_EQ(canopen::sync_frame().id, 0x080u);
  EXPECT_EQ(canopen::sync_frame().len, 0);
  const auto rpdo = canopen::decode_rpdo1(canopen::rpdo1_frame(5, 0x0F, -120));
  ASSERT_TRUE(rpdo);
  EXPECT_EQ(rpdo->controlword, 0x0F);
  EXPECT_EQ(rpdo->target_torque, -120);
  const auto tpdo = canopen::decode_tpdo1(canopen::tpdo1_frame(5, 0x0627, -2000000));
  ASSERT_TRUE(tpdo);
  EXPECT_EQ(tpdo->statusword, 0x0627);
  EXPECT_EQ(tpdo->position, -2000000);
  CanFrame wrong = canopen::tpdo1_frame(5, 0x0627, 1);
  wrong.len = 5;
  EXPECT_FALSE(canopen::decode_tpdo1(wrong)) << "wrong DLC";
}

TEST(Cia402, StatuswordDecodesEveryStateOfDesignSection6) {
  EXPECT_EQ(cia402::decode_statusword(0x0040), PowerState::kSwitchOnDisabled);
  EXPECT_EQ(cia402::decode_statusword(0x0021), PowerState::kReadyToSwitchOn);
  EXPECT_EQ(cia402::decode_statusword(0x0023), PowerState::kSwitchedOn);
  EXPECT_EQ(cia402::decode_statusword(0x0027), PowerState::kOperationEnabled);
  EXPECT_EQ(cia402::decode_statusword(0x0637), PowerState::kOperationEnabled);
  EXPECT_EQ(cia402::decode_statusword(0x0007), PowerState::kQuickStopActive);
  EXPECT_EQ(cia402::decode_statusword(0x0008), PowerState::kFault);
  EXPECT_EQ(cia402::decode_statusword(0x0218), PowerState::kFault);
  EXPECT_EQ(cia402::decode_statusword(0x000F), PowerState::kFaultReactionActive);
  for (PowerState s :
       {PowerState::kSwitchOnDisabled, PowerState::kReadyToSwitchOn, PowerState::kSwitchedOn,
        PowerState::kOperationEnabled, PowerState::kQuickStopActive, PowerState::kFault}) {
    EXPECT_EQ(cia402::decode_statusword(cia402::encode_statusword(s)), s) << to_string(s);
  }
  EXPECT_EQ(cia402::describe_statusword(0x0627),
            "0x0627 operation enabled, remote, target reached");
}

TEST(Cia402, ControlwordsWalkTheDriveToOperationEnabledAndBack) {
  PowerState s = PowerState::kSwitchOnDisabled;
  std::uint16_t previous = 0;
  int steps = 0;
  while (s != PowerState::kOperationEnabled) {
    const auto cw = cia402::step_towards_enabled(s);
    ASSERT_TRUE(cw) << to_string(s);
    s = cia402::apply_controlword(s, *cw, previous);
    previous = *cw;
    ASSERT_LT(++steps, 4);
  }
  EXPECT_EQ(steps, 3) << "0x06, 0x07, 0x0F";
  EXPECT_EQ(cia402::apply_controlword(s, cia402::kCwShutdown, 0x0F), PowerState::kReadyToSwitchOn);
  EXPECT_EQ(cia402::apply_controlword(s, cia402::kCwQuickStop, 0x0F), PowerState::kQuickStopActive);
  EXPECT_EQ(cia402::apply_controlword(s, cia402::kCwDisableVoltage, 0x0F),
            PowerState::kSwitchOnDisabled);
  EXPECT_FALSE(cia402::step_towards_enabled(PowerState::kFault)) << "needs a fault reset";
  // A fault reset is the rising edge of bit 7, not its level.
  EXPECT_EQ(cia402::apply_controlword(PowerState::kFault, 0x80, 0x00),
            PowerState::kSwitchOnDisabled);
  EXPECT_EQ(cia402::apply_controlword(PowerState::kFault, 0x80, 0x80), PowerState::kFault);
  EXPECT_EQ(cia402::apply_controlword(PowerState::kFault, 0x0F, 0x00), PowerState::kFault);
}

TEST(Cia402, PdoMappingInvalidatesFirstAndDisablesTheUnusedPdos) {
  const auto m = cia402::pdo_mapping(4, false);
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.front().at.index, 0x1400);
  EXPECT_EQ(m.front().value, 0x80000204u) << "RPDO1 invalid while its mapping changes";
  bool rpdo_valid_last = false;
  for (const auto& e : m) {
    if (e.at.index == 0x1400 && e.at.subindex == 1) rpdo_valid_last = e.value == 0x204;
  }
  EXPECT_TRUE(rpdo_valid_last);
  int entries = 0;
  for (const auto& e : m) {
    if (e.at.index == 0x1A00 && e.at.subindex == 2) {
      EXPECT_EQ(e.value, 0x60640020u);
    }
    if (e.at.index == 0x1801 && e.at.subindex == 1) {
      EXPECT_EQ(e.value, 0x80000284u);
    }
    entries += e.final ? 1 : 0;
  }
  EXPECT_GT(entries, 10);
  EXPECT_TRUE(cia402::is_cob_id({0x1400, 1}));
  EXPECT_TRUE(cia402::is_cob_id({0x1803, 1}));
  EXPECT_FALSE(cia402::is_cob_id({0x1600, 1}));
}

TEST(Odrive, IdsPayloadsAndBothFirmwaresErrors) {
  EXPECT_EQ(odrive::frame_id(3, odrive::kSetInputTorque), 0x06Eu);
  const CanFrame t = odrive::set_input_torque(3, 0.25f);
  EXPECT_EQ(t.len, 4);
  EXPECT_EQ(get_f32(t, 0), 0.25f);
  const CanFrame r = odrive::request(3, odrive::kGetEncoderEstimates, 8);
  EXPECT_TRUE(r.rtr);
  EXPECT_EQ(r.id, 0x069u);
  const auto hb = odrive::decode_heartbeat(odrive::heartbeat(3, {0x800, 1, 0}));
  ASSERT_TRUE(hb);
  EXPECT_EQ(hb->axis_error, 0x800u);
  EXPECT_EQ(hb->axis_state, 1);
  CanFrame short_hb = odrive::heartbeat(3, {0, 8, 0});
  short_hb.len = 4;
  EXPECT_FALSE(odrive::decode_heartbeat(short_hb));
  EXPECT_EQ(odrive::describe_axis_error(odrive::Firmware::k05, 0x800),
            "0x00000800 WATCHDOG_TIMER_EXPIRED");
  EXPECT_EQ(odrive::describe_axis_error(odrive::Firmware::k06, 0x01000000),
            "0x01000000 WATCHDOG_TIMER_EXPIRED");
  EXPECT_EQ(odrive::describe_axis_error(odrive::Firmware::k06, 0x1200),
            "0x00001200 DC_BUS_UNDER_VOLTAGE | CURRENT_LIMIT_VIOLATION");
  EXPECT_EQ(odrive::describe_axis_error(odrive::Firmware::k05, 0x80000001),
            "0x80000001 INVALID_STATE | unknown bits 0x80000000");
  EXPECT_EQ(odrive::clear_errors(3, odrive::Firmware::k05).len, 0);
  EXPECT_EQ(odrive::clear_errors(3, odrive::Firmware::k06).len, 1);
  const auto v = odrive::decode_version(odrive::version_frame(3, {2, 4, 4, 58, 0, 6, 10}));
  ASSERT_TRUE(v);
  EXPECT_EQ(odrive::firmware_of(*v), odrive::Firmware::k06);
  EXPECT_FALSE(odrive::firmware_of({2, 3, 6, 56, 0, 4, 12})) << "0.4 is not spoken";
  const auto e = odrive::decode_encoder_estimates(odrive::encoder_estimates(3, {1.5f, -2.0f}));
  ASSERT_TRUE(e);
  EXPECT_EQ(e->position_turns, 1.5f);
  EXPECT_EQ(e->velocity_turns_per_s, -2.0f);
  EXPECT_EQ(odrive::axis_state_name(8), "CLOSED_LOOP_CONTROL");
}

// 0.6's Get_Error (ODriveArduino can_simple_messages.hpp, Get_Error_msg_t): Active_Errors in
// bytes 0-3, Disarm_Reason in 4-7, little-endian.
TEST(Odrive, GetErrorCarriesTheActiveErrorsAndTheDisarmReason) {
  const CanFrame f = odrive::error_status(3, {0x00000000, 0x00000200});
  EXPECT_EQ(f.id, 0x063u);
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.data[4], 0x00);
  EXPECT_EQ(f.data[5], 0x02);
  const auto e = odrive::decode_error_status(f);
  ASSERT_TRUE(e);
  EXPECT_EQ(e->active_errors, 0u);
  EXPECT_EQ(e->disarm_reason, 0x200u);
  CanFrame short_frame = f;
  short_frame.len = 4;
  EXPECT_FALSE(odrive::decode_error_status(short_frame));
  EXPECT_FALSE(odrive::decode_error_status(odrive::request(3, odrive::kGetError, 8)));
}

TEST(BusLoad, WorstCaseFrameLengthsAndTheLoadOfEachProfile) {
  EXPECT_EQ(worst_case_frame_bits(0), 55);
  EXPECT_EQ(worst_case_frame_bits(8), 135);
  CanSettings s;
  s.profile = Profile::kCia402;
  s.bitrate = 1'000'000;
  s.cia402.master_heartbeat_ms = 0;
  s.cia402.heartbeat_producer_ms = 100;
  const BusLoad cia = bus_load(s, 1000.0);
  // SYNC 55 + RPDO (4 bytes) 95 + TPDO (6 bytes) 115 = 265 bits a tick, plus a 1-byte
  // heartbeat (65 bits) every 100 ticks.
  EXPECT_EQ(worst_case_frame_bits(1), 65);
  EXPECT_NEAR(cia.bits_per_tick, 265 + 0.65, 1e-9);
  EXPECT_NEAR(cia.load, cia.bits_per_tick * 1000 / 1e6, 1e-12);
  EXPECT_EQ(bus_load_notes(s, 1000.0).size(), 2u) << "25 % is below the warning";
  s.bitrate = 250'000;
  const auto notes = bus_load_notes(s, 1000.0);
  ASSERT_EQ(notes.size(), 3u);
  EXPECT_NE(notes[2].find("warning: can bus load 106.3 %"), std::string::npos) << notes[2];
  EXPECT_NE(notes[2].find("cannot carry"), std::string::npos) << notes[2];
  s.profile = Profile::kOdrive;
  s.bitrate = 1'000'000;
  const BusLoad od = bus_load(s, 1000.0);
  EXPECT_NEAR(od.frames_per_tick, 3.01, 1e-9) << "torque, request, answer, heartbeats";
}

}  // namespace
}  // namespace hapticd::drivers::can
