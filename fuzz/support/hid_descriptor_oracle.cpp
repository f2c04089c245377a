#include "support/hid_descriptor_oracle.h"

#include <algorithm>
#include <charconv>
#include <cstddef>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "drivers/hid/descriptor_builder.h"
#include "drivers/hid/pid_protocol.h"
#include "drivers/hid/report_descriptor.h"
#include "support/check.h"
#include "support/hid_bits_oracle.h"

namespace hapticd::fuzz {
namespace {

namespace hid = hapticd::drivers::hid;
using Bytes = std::vector<std::uint8_t>;

void check_error(const std::string& e, std::size_t size) {
  require(!e.empty(), "a refused descriptor says why");
  if (e.rfind("byte ", 0) == 0) {
    std::size_t at = 0;
    const auto [end, ec] = std::from_chars(e.data() + 5, e.data() + e.size(), at);
    require(ec == std::errc() && at < size && end[0] == ':', "the byte named is in the input", e);
    return;
  }
  // Errors about the descriptor as a whole name no byte (tests/hid/descriptor_test.cpp).
  const bool whole = size == 0 || size > hid::kMaxDescriptorSize ||
                     e.find("still open at the end of the descriptor") != std::string::npos ||
                     e.find("before any Report ID") != std::string::npos;
  require(whole, "an item's error names its byte", e);
}

void check_parsed(const hid::ParsedDescriptor& d) {
  require(d.fields.size() <= 1024, "at most 1024 fields");
  std::vector<std::uint64_t> used(d.reports.size(), 0);  // bits the fields so far fill
  for (const hid::ReportInfo& r : d.reports) {
    require(d.find_report(r.kind, r.id) == &r, "reports are unique by kind and id");
    require((r.id != 0) == d.numbered, "numbered descriptors number every report, others none");
    require(r.bits > 0 && r.data_bytes() <= 4096, "a report is 1 bit to 4096 bytes");
  }
  for (const hid::ReportField& f : d.fields) {
    const hid::ReportInfo* r = d.find_report(f.kind, f.report_id);
    require(r != nullptr, "find_report finds every field's report");
    require(f.bit_size >= 1 && f.bit_size <= 256 && f.count >= 1 && f.count <= 4096,
            "Report Size 1..256 and Count 1..4096");
    require(f.usages.size() <= 4096 && f.collections.size() <= 64, "usages and depth bounded");
    require(f.logical_min < 0 || f.logical_max >= 0, "a maximum is signed after a minimum < 0");
    const auto i = static_cast<std::size_t>(r - d.reports.data());
    require(f.bit_offset == used[i], "a report's fields follow one another");
    used[i] += std::uint64_t{f.bit_size} * f.count;
    require(used[i] <= r->bits, "every field lies inside its report's bits");
  }
  for (std::size_t i = 0; i < d.reports.size(); ++i)
    require(used[i] == d.reports[i].bits, "a report is its fields' bits");
}

// The values a slot's bits can hold, as get_slot reads them.
std::pair<std::int64_t, std::int64_t> representable(const hid::Slot& s) {
  const std::int64_t top = std::int64_t{1} << (s.bit_size - (s.is_signed ? 1 : 0));
  return {s.is_signed ? -top : 0, top - 1};
}

bool outside(const hid::Slot& s, std::int64_t v) { return v < s.logical_min || v > s.logical_max; }

// A report of `ref` with data from `fill`, one slot written and read back.
void check_slot(const hid::ReportRef& ref, bool numbered, const hid::Slot& s,
                std::span<const std::uint8_t> fill) {
  if (!s.present) return;
  require(ref.present && s.bit_size >= 1 && s.bit_size <= 32, "a slot is 1..32 bits of a report");
  require(std::uint64_t{s.bit_offset} + s.bit_size <= 8 * std::uint64_t{ref.data_bytes},
          "a slot lies inside its report");
  Bytes rep = hid::make_report(ref, numbered);
  const std::span<std::uint8_t> data = hid::data_of(std::span<std::uint8_t>(rep), ref, numbered);
  for (std::size_t i = 0; i < data.size() && !fill.empty(); ++i) data[i] = fill[i % fill.size()];
  const auto [lo, hi] = representable(s);
  const std::int64_t read = hid::get_slot(data, s);
  require(read >= lo && read <= hi, "get_slot reads a value of the slot's width");
  const std::int64_t mid = lo + static_cast<std::int64_t>(read - lo) / 2;
  for (const std::int64_t v : {s.logical_min, s.logical_max, mid, hid::null_value(s)}) {
    const Bytes before(data.begin(), data.end());
    hid::set_slot(data, s, v);
    const Bytes expect =
        put_bits_model(before, s.bit_offset, s.bit_size, static_cast<std::uint32_t>(v));
    require(std::equal(data.begin(), data.end(), expect.begin(), expect.end()),
            "set_slot writes the slot's bits only");
    if (v >= lo && v <= hi) require(hid::get_slot(data, s) == v, "set_slot then get_slot");
  }
  // null_value() is the last value written. It must read outside the logical range whenever
  // some value of the slot's width does (an end of the width is then outside).
  if (outside(s, lo) || outside(s, hi)) {
    require(outside(s, hid::get_slot(data, s)), "null_value reads outside the logical range");
  }
}

// pid_status over `data`, bit by bit from pid_protocol.h's table.
void check_status(std::span<const std::uint8_t> data, const hid::PidLayout& l) {
  const std::pair<const hid::Slot&, std::uint32_t> table[] = {
      {l.st_paused, hid::kPidPaused},
      {l.st_actuators_enabled, hid::kPidActuatorsDisabled},
      {l.st_safety_switch, hid::kPidSafetySwitchOff},
      {l.st_override, hid::kPidOverride},
      {l.st_power, hid::kPidPowerOff},
      {l.st_playing, hid::kPidEffectStopped}};
  std::uint32_t want = 0;
  for (const auto& [slot, bit] : table) {
    const bool when_one = bit == hid::kPidPaused || bit == hid::kPidOverride;
    if (slot.present && (hid::get_slot(data, slot) != 0) == when_one) want |= bit;
  }
  require(hid::pid_status(data, l) == want, "pid_status sets the bits its fields say, no others");
}

// The reports the layout found: each of its kind, made, and recognised by id and length.
void check_pid_reports(const hid::ParsedDescriptor& d, const hid::PidLayout& l,
                       std::span<const std::uint8_t> fill) {
  using K = hid::ReportKind;
  const struct {
    const hid::ReportRef& ref;
    K kind;
    bool required;
  } reports[] = {{l.position_report, K::kInput, true}, {l.set_effect, K::kOutput, true},
                 {l.set_constant, K::kOutput, true},   {l.effect_operation, K::kOutput, true},
                 {l.device_control, K::kOutput, true}, {l.create_effect, K::kFeature, true},
                 {l.block_load, K::kFeature, true},    {l.device_gain, K::kOutput, false},
                 {l.block_free, K::kOutput, false},    {l.state, K::kInput, false}};
  for (const auto& [ref, kind, required] : reports) {
    require(ref.present || !required, "a found layout has every report the profile needs");
    if (!ref.present) continue;
    const hid::ReportInfo* info = d.find_report(ref.kind, ref.id);
    require(ref.kind == kind && info != nullptr && info->data_bytes() == ref.data_bytes,
            "a PID report is the descriptor's report of its kind");
    const Bytes rep = hid::make_report(ref, l.numbered);
    require(hid::is_report(rep, ref, l.numbered) &&
                hid::data_of(std::span<const std::uint8_t>(rep), ref, l.numbered).size() ==
                    ref.data_bytes,
            "make_report makes the report, data_of finds its data");
    // The fill cut to the report's size (or shorter), as a device might send it.
    const Bytes cut(fill.begin(),
                    fill.begin() + static_cast<std::ptrdiff_t>(std::min(fill.size(), rep.size())));
    const bool id_ok = (!l.numbered && kind == K::kInput) || (!cut.empty() && cut[0] == ref.id);
    require(hid::is_report(cut, ref, l.numbered) == (id_ok && cut.size() == rep.size()),
            "is_report: the id and the length");
    check_status(hid::data_of(std::span<const std::uint8_t>(cut), ref, l.numbered), l);
  }
}

// Every slot and choice the layout found, written and read back in its own report.
void check_pid_slots(const hid::PidLayout& l, std::span<const std::uint8_t> fill) {
  require(!l.positions.empty() && l.sc_magnitude.present && l.bl_block.present,
          "a found layout has the fields find_pid_layout needs");
  std::vector<const hid::Slot*> input{&l.sequence};
  for (const hid::Slot& p : l.positions) {
    require(p.present, "every joint's position is found");
    input.push_back(&p);
  }
  require(l.positions.size() == 1 ||
              (l.se_axis_x.present && l.se_axis_y.present && l.se_direction_y.present),
          "two joints' layout has both axes' enables and Directions");
  const std::pair<const hid::ReportRef&, std::vector<const hid::Slot*>> slots[] = {
      {l.position_report, input},
      {l.set_effect,
       {&l.se_block, &l.se_duration, &l.se_trigger_repeat, &l.se_sample_period, &l.se_start_delay,
        &l.se_gain, &l.se_trigger_button, &l.se_axis_x, &l.se_axis_y, &l.se_direction_enable,
        &l.se_direction, &l.se_direction_y}},
      {l.set_constant, {&l.sc_block, &l.sc_magnitude}},
      {l.effect_operation, {&l.eo_block, &l.eo_loop_count}},
      {l.block_load, {&l.bl_block, &l.bl_ram_pool}},
      {l.device_gain, {&l.dg_gain}},
      {l.block_free, {&l.bf_block}},
      {l.state,
       {&l.st_paused, &l.st_actuators_enabled, &l.st_safety_switch, &l.st_override, &l.st_power,
        &l.st_playing}}};
  for (const auto& [ref, list] : slots) {
    for (const hid::Slot* s : list) check_slot(ref, l.numbered, *s, fill);
  }
  const std::pair<const hid::ReportRef&, std::vector<const hid::Choice*>> choices[] = {
      {l.set_effect, {&l.se_constant}},
      {l.effect_operation, {&l.eo_start, &l.eo_stop}},
      {l.device_control, {&l.dc_enable, &l.dc_disable, &l.dc_stop_all, &l.dc_reset}},
      {l.create_effect, {&l.ce_constant}},
      {l.block_load, {&l.bl_success, &l.bl_full, &l.bl_error}}};
  for (const auto& [ref, list] : choices) {
    for (const hid::Choice* c : list) {
      check_slot(ref, l.numbered, c->slot, fill);
      if (!c->slot.present) continue;
      Bytes rep = hid::make_report(ref, l.numbered);
      const std::span<std::uint8_t> data =
          hid::data_of(std::span<std::uint8_t>(rep), ref, l.numbered);
      hid::choose(data, *c);
      const auto [lo, hi] = representable(c->slot);
      if (c->value >= lo && c->value <= hi) require(hid::chosen(data, *c), "choose then chosen");
    }
  }
}

}  // namespace

void check_hid_descriptor(std::span<const std::uint8_t> bytes, bool with_sequence) {
  const hid::DescriptorParse p = hid::parse_report_descriptor(bytes);
  if (!p.descriptor) return check_error(p.error, bytes.size());
  require(p.error.empty(), "a parsed descriptor has no error");
  check_parsed(*p.descriptor);
  const std::uint32_t sequence = with_sequence ? hid::kReferenceSequenceUsage : 0;
  const hid::PidFind f = hid::find_pid_layout(*p.descriptor, hid::kGenericDesktopX, sequence);
  require(f.layout.has_value() == f.error.empty(), "a PID layout, or an error naming the gap");
  if (!f.layout) return;
  check_pid_reports(*p.descriptor, *f.layout, bytes);
  check_pid_slots(*f.layout, bytes);
  // The same descriptor as a stick of two axes: X and Y, one effect each.
  const std::uint32_t xy[] = {hid::kGenericDesktopX, hid::kGenericDesktopY};
  const hid::PidFind two = hid::find_pid_layout(*p.descriptor, xy, sequence);
  require(two.layout.has_value() == two.error.empty(), "two axes: a layout, or the gap named");
  if (two.layout) check_pid_slots(*two.layout, bytes);
}

}  // namespace hapticd::fuzz
