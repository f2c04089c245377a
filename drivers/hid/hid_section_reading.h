// Reading device.hid (hid_section.cpp) and its report layout (report_section.cpp): the reading
// state and helpers the two files share. Internal to the HID codec module.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "config/schema_reader.h"
#include "drivers/hid/hid_settings.h"

namespace hapticd::drivers::hid::section {

using config::schema::Diagnostics;
using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;
using config::schema::read_hex;

// Reading state shared by the helpers: where each sub-key is (for errors found after
// reading) and whether anything went wrong in this section.
struct Ctx {
  Diagnostics& d;
  std::map<std::string, YAML::Mark> marks;  // path below device.hid.report -> key mark
  std::size_t errors_before;
  bool failed() const { return d.messages().size() != errors_before; }
  void mark(const Field& f, const std::string& rel) {
    if (f.present) marks[rel] = f.key_mark;
  }
  // Reports "device.hid.report.<rel>: what" at the closest key recorded for `rel`.
  void error_at(const std::string& rel, const std::string& what, const YAML::Mark& fallback);
};

// Takes `key`; reports it missing (with `why`) when `why` is given and it is absent.
Field take(MapReader& m, const char* key, const char* why = nullptr);
// A raw value written into a field (an enable's on/off, a feature's value): a number, or an
// unsigned integer in 0x hexadecimal as ids and masks are.
void raw_value(MapReader& m, const Field& f, double& out);
// Where one field is and what it holds (drivers/field/field_schema.h).
FieldSpec read_spec(MapReader& m, bool quantity);
// A key given without a value (`--set device.hid.report.output.enable=`) is absent: that is
// how an optional mapping of an example file is removed from the command line.
bool absent(const Field& f);
std::optional<FieldSpec> optional_field(MapReader& parent, Ctx& c, const std::string& rel,
                                        const char* key, bool quantity);

// The entries of a list form (`positions`, `forces`): one mapping per joint, joint i entry i.
// Nothing for a list that is not one of 1..kMaxJoints entries (reported at its key).
std::vector<Field> list_entries(Ctx& c, const Field& f, const std::string& rel);
// The one-joint key or its list form, never both: which one names the joints' fields.
// `listed`: the list form was given.
std::vector<Field> joint_fields(MapReader& m, Ctx& c, const char* one, const char* list,
                                const std::string& parent, const char* why, bool& listed);

// device.hid.report (profile report), into s.report.
void read_report_profile(MapReader& hid, Ctx& c, const config::Config& cfg, HidSettings& s);

}  // namespace hapticd::drivers::hid::section
