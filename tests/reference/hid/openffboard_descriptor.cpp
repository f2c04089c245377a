// OpenFFBoard's report descriptor (see openffboard_descriptor.h).
#include "openffboard_descriptor.h"

#include "hid_items.h"

namespace hapticd::reference {
namespace {

// ffb_defs.h: the effect types in the descriptor's order (Create New Effect's value - 1).
constexpr std::uint8_t kTypes[] = {0x26, 0x27, 0x30, 0x31, 0x32, 0x33,
                                   0x34, 0x40, 0x41, 0x42, 0x43};

void block_index(Items& d, int flags_kind) {
  d.use(0x22).logical(1, 40).physical(1, 40).bits(8, 1);
  if (flags_kind == 0)
    d.out(kVar);
  else
    d.feature(kVar);
}

void effect_types(Items& d, bool feature) {
  d.use(0x25).open(kLogical);
  for (std::uint8_t t : kTypes) d.use(t);
  d.logical(1, 11).physical(1, 11).bits(8, 1);
  if (feature)
    d.feature(kArr);
  else
    d.out(kArr);
  d.close();
}

// HIDDESC_GAMEPAD_16B and HIDDESC_CTRL_REPORTS.
void gamepad_and_commands(Items& d) {
  d.open(kPhysical).id(1).page(0x09).item(0x18, 1).item(0x28, 64).logical(0, 1).bits(1, 64).in(
      kVar);
  d.page(0x01);
  for (int u : {0x30, 0x31, 0x32, 0x33, 0x34, 0x35, 0x37, 0x36}) d.use(u);
  d.logical(-32767, 32767).bits(16, 8).in(kVar).close();
  d.page(0xFF00).use(0).open(kApplication);
  for (bool output : {true, false}) {
    d.id(0xA1);
    const int sizes[] = {8, 16, 8, 32, 64, 64};
    for (int i = 0; i < 6; ++i) {
      d.use(i + 1).logical(0, 4).bits(sizes[i], 1);
      if (output)
        d.out(kVar);
      else
        d.in(kVar);
    }
  }
  d.close();
}

// The reports both descriptors share after the Set Condition report (usb_hid_1ffb_desc.c
// lines 137-226, usb_hid_2ffb_desc.c lines 328-652).
void other_reports(Items& d) {
  // HIDDESC_FFB_SETPERIODICREP (magnitude, offset, phase, period).
  d.use(0x6E).open(kLogical).id(4);
  block_index(d, 0);
  d.use(0x70).logical(0, 32767).physical(0, 32767).bits(16, 1).out(kVar);
  d.use(0x6F).logical(-32767, 32767).physical(-32767, 32767).bits(16, 1).out(kVar);
  d.use(0x71).item(0x64, 0x14).item(0x54, -2).logical(0, 35999).physical(0, 35999).out(kVar);
  d.use(0x72).item(0x64, 0x1003).item(0x54, -3).logical(0, 32767).physical(0, 32767);
  d.bits(32, 1).out(kVar).item(0x64, 0).item(0x54, 0).close();
  // HIDDESC_FFB_SETCFREP.
  d.use(0x73).open(kLogical).id(5);
  block_index(d, 0);
  d.use(0x70).logical(-32767, 32767).physical(-32767, 32767).bits(16, 1).out(kVar).close();
  // HIDDESC_FFB_SETRAMPREP.
  d.use(0x74).open(kLogical).id(6);
  block_index(d, 0);
  d.use(0x75).use(0x76).logical(-32767, 32767).physical(-32767, 32767).bits(16, 2).out(kVar);
  d.close();
  // HIDDESC_FFB_EFOPREP, HIDDESC_FFB_BLOCKFREEREP.
  d.page(0x0F).use(0x77).open(kLogical).id(0x0A);
  block_index(d, 0);
  d.use(0x78).open(kLogical).use(0x79).use(0x7A).use(0x7B).logical(1, 3).bits(8, 1).out(kArr);
  d.close().use(0x7C).logical(0, 255).physical(0, 255).out(kVar).close();
  d.use(0x90).open(kLogical).id(0x0B);
  block_index(d, 0);
  d.close();
  // HIDDESC_FFB_DEVCTRLREP: eight one-bit variables (the last usage repeats), and Device Gain.
  d.use(0x95).open(kLogical).id(0x0C).use(0x96).open(kLogical);
  for (int u = 0x97; u <= 0x9C; ++u) d.use(u);
  d.logical(1, 6).bits(1, 8).out(kVar).close().close();
  d.use(0x7D).open(kLogical).id(0x0D).use(0x7E).logical(0, 255).physical(0, 10000);
  d.bits(8, 1).out(kVar).close();
  // HIDDESC_FFB_NEWEFREP, HIDDESC_FFB_BLOCKLOADREP, HIDDESC_FFB_POOLREP.
  d.use(0xAB).open(kLogical).id(0x11);
  effect_types(d, true);
  d.page(0x01).use(0x3B).logical(0, 511).physical(0, 511).bits(10, 1).feature(kVar);
  d.bits(6, 1).feature(0x01).close();
  d.page(0x0F).use(0x89).open(kLogical).id(0x12);
  block_index(d, 1);
  d.use(0x8B).open(kLogical).use(0x8C).use(0x8D).use(0x8E).logical(1, 3).physical(1, 3);
  d.bits(8, 1).feature(kArr).close();
  d.use(0xAC).logical(0, 65535).physical(0, 65535).bits(16, 1).feature(kArr).close();
  d.use(0x7F).open(kLogical).id(0x13).use(0x80).bits(16, 1).logical(0, 65535).physical(0, 65535);
  d.feature(kVar).use(0x83).logical(0, 255).physical(0, 255).bits(8, 1).feature(kVar);
  d.use(0xA9).use(0xAA).bits(1, 2).logical(0, 1).physical(0, 1).feature(kVar);
  d.bits(6, 1).feature(kConst).close();
}
// HIDDESC_FFB_SETEFREP and the tail of the Set Effect report of each descriptor: one axis
// (usb_hid_1ffb_desc.c lines 28-76) or two (usb_hid_2ffb_desc.c lines 182-231: Axes Enable X
// and Y, Direction Enable at bit 2, two Direction and two Type Specific Block Offset instances).
void set_effect_report(Items& d, int axes) {
  d.use(0x21).open(kLogical).id(1);
  block_index(d, 0);
  effect_types(d, false);
  d.use(0x50).use(0x54).use(0x51).use(0xA7).logical(0, 32767).physical(0, 32767);
  d.item(0x64, 0x1003).item(0x54, -3).bits(16, 4).out(kVar).item(0x54, 0).item(0x64, 0);
  d.use(0x52).logical(0, 255).physical(0, 10000).bits(8, 1).out(kVar);
  d.use(0x53).logical(1, 8).physical(1, 8).bits(8, 1).out(kVar);
  if (axes == 1) {
    d.use(0x55).open(kLogical).page(0x01).use(0x30).logical(0, 0).bits(1, 1).out(kVar).close();
    d.page(0x0F).use(0x56).item(0x94, 1).out(kVar).item(0x94, 6).out(kConst);
    d.use(0x57).open(kLogical).item(0x08, 0x000A0001).item(0x64, 0x14).logical(0, 36000);
    d.physical(0, 36000).item(0x64, 0).bits(16, 1).out(kVar).item(0x54, 0).close();
    d.page(0x0F).use(0x58).open(kLogical).item(0x08, 0x000A0001).item(0x24, 32765);
    d.bits(16, 1).out(kVar).close().close();
    return;
  }
  d.use(0x55).open(kLogical).page(0x01).use(0x30).use(0x31).logical(0, 1).bits(1, 2).out(kVar);
  d.close().page(0x0F).use(0x56).item(0x94, 1).out(kVar).item(0x94, 5).out(kConst);
  d.use(0x57).open(kLogical).item(0x08, 0x000A0001).item(0x08, 0x000A0002).item(0x64, 0x14);
  d.item(0x54, -2).logical(0, 36000).physical(0, 36000).item(0x64, 0).bits(16, 2).out(kVar);
  d.item(0x54, 0).item(0x64, 0).close();
  d.page(0x0F).use(0x58).open(kLogical).item(0x08, 0x000A0001).item(0x08, 0x000A0002);
  d.item(0x24, 32765).bits(16, 2).out(kVar).close().close();
}

// The Set Condition report, which the descriptors write out by axis count: one Type Specific
// Block Offset of 2 bits after a 6-bit Parameter Block Offset (usb_hid_1ffb_desc.c lines
// 80-135), or two after a 4-bit one (usb_hid_2ffb_desc.c lines 271-326).
void condition_report(Items& d, int axes) {
  d.use(0x5F).open(kLogical).id(3);
  block_index(d, 0);
  d.use(0x23).logical(0, 3).physical(0, 3).bits(axes == 1 ? 6 : 4, 1).out(kVar);
  d.use(0x58).open(kLogical).item(0x08, 0x000A0001);
  if (axes == 2) d.item(0x08, 0x000A0002);
  d.bits(2, axes).out(kVar).close();
  d.logical(-32768, 32767).physical(-32768, 32767).use(0x60).bits(16, 1).out(kVar);
  d.use(0x61).use(0x62).item(0x94, 2).out(kVar);
  d.logical(0, 32767).physical(0, 32767).use(0x63).use(0x64).bits(16, 2).out(kVar);
  d.use(0x65).item(0x94, 1).out(kVar).close();
}

void pid_reports(Items& d, int axes) {
  // HIDDESC_FFB_STATEREP: five one-bit flags (paused, enabled, safety, power, playing).
  d.page(0x0F).use(0x92).open(kLogical).id(2);
  for (int u : {0x9F, 0xA0, 0xA4, 0xA6, 0x94}) d.use(u);
  d.logical(0, 1).physical(0, 1).bits(1, 5).in(kVar).bits(1, 3).in(kConst).close();
  set_effect_report(d, axes);
  // HIDDESC_FFB_SETENVREP.
  d.use(0x5A).open(kLogical).id(2);
  block_index(d, 0);
  d.use(0x5B).use(0x5D).logical(0, 32767).physical(0, 32767).bits(16, 2).out(kVar);
  d.use(0x5C).use(0x5E).item(0x64, 0x1003).item(0x54, -3).item(0x24, 32767).item(0x44, 32767);
  d.item(0x74, 32).out(kVar).item(0x44, 0).item(0x64, 0).item(0x54, 0).close();
  condition_report(d, axes);
  other_reports(d);
}

}  // namespace

std::vector<std::uint8_t> openffboard_descriptor(int axes) {
  Items d;
  d.page(0x01).use(0x04).open(kApplication);  // Joystick
  gamepad_and_commands(d);
  pid_reports(d, axes);
  d.close();
  return d.bytes;
}

}  // namespace hapticd::reference
