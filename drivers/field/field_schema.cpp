#include "drivers/field/field_schema.h"

#include <string>
#include <vector>

namespace hapticd::drivers::field {
namespace {

using config::schema::Field;
using config::schema::integer;
using config::schema::IntRange;
using config::schema::MapReader;
using config::schema::number;
using config::schema::Range;

// What `type:` takes, in FieldType's order, named where the types are (field.h).
std::vector<std::string> field_type_names() {
  std::vector<std::string> names;
  for (int t = 0; t <= static_cast<int>(FieldType::kI24); ++t) {
    names.emplace_back(to_string(static_cast<FieldType>(t)));
  }
  return names;
}

// The field's type or width: `type` (which has its width), or `bits` with `signed`.
void read_type(MapReader& m, FieldSpec& f) {
  const Field type = m.take("type");
  const Field bits = m.take("bits");
  const Field sign = m.take("signed");
  if (!type.present && !bits.present) {
    m.missing("type",
              "one of u8, i8, u16, i16, u24, i24, u32, i32, f32; or bits: N (1..32) for a field "
              "of N bits");
  } else if (type.present && bits.present) {
    m.diag().error(bits.key_mark, bits.path,
                   "give type or bits, not both (a type has its width: u16 is 16 bits)");
  } else if (type.present) {
    static const std::vector<std::string> kNames = field_type_names();
    if (const auto t = config::schema::read_choice(m.diag(), type, kNames)) {
      f = typed(static_cast<FieldType>(*t), f.byte);
    }
  } else {
    integer(m, bits, IntRange::between(1, kMaxFieldBits), f.bits);
  }
  if (sign.present && type.present) {
    m.diag().error(sign.key_mark, sign.path, "only with bits: the type says whether it is signed");
  } else if (const auto v = config::schema::read_bool(m.diag(), sign)) {
    f.is_signed = *v;
  }
}

}  // namespace

FieldSpec read_spec(MapReader& m, std::size_t max_byte, bool quantity) {
  FieldSpec f;
  const Field byte = m.take("byte");
  if (!byte.present) m.missing("byte", "the field's byte offset in the message");
  integer(m, byte, IntRange::between(0, static_cast<long long>(max_byte)), f.byte);
  read_type(m, f);
  const Field bit = m.take("bit");
  integer(m, bit, IntRange::between(0, 7), f.bit);
  if (bit.present && f.is_float && f.bit != 0) {
    m.diag().error(bit.key_mark, bit.path, "an f32 starts at bit 0 of its byte");
  }
  if (const auto e = config::schema::read_choice(m.diag(), m.take("endian"), {"little", "big"})) {
    f.endian = *e == 0 ? Endian::kLittle : Endian::kBig;
  }
  if (quantity) {
    const Field scale = m.take("scale");
    if (!scale.present) m.missing("scale", "SI units per count");
    number(m, scale, Range::any(), f.scale);
    if (scale.present && f.scale == 0.0) {
      m.diag().error(scale.key_mark, scale.path,
                     "must not be 0: every count would read as the same value");
    }
    number(m, m.take("offset"), Range::any(), f.offset);
  }
  return f;
}

}  // namespace hapticd::drivers::field
