#include "drivers/hid/descriptor_builder.h"

#include "drivers/hid/pid_protocol.h"

namespace hapticd::drivers::hid {
namespace {

constexpr std::uint32_t kData = kMainVariable;  // Data, Variable, Absolute
constexpr std::uint32_t kArray = 0;             // Data, Array, Absolute
constexpr std::uint8_t kApplication = 1, kLogical = 2, kPhysical = 0;

}  // namespace

void DescriptorBuilder::emit(std::uint8_t type, std::uint8_t tag, std::uint32_t value,
                             std::uint8_t size) {
  const std::uint8_t code = size == 4 ? 3 : size;
  bytes_.push_back(static_cast<std::uint8_t>(tag << 4 | type << 2 | code));
  for (std::uint8_t i = 0; i < size; ++i)
    bytes_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

DescriptorBuilder& DescriptorBuilder::unsigned_item(std::uint8_t type, std::uint8_t tag,
                                                    std::uint32_t value) {
  emit(type, tag, value, value <= 0xFF ? 1 : value <= 0xFFFF ? 2 : 4);
  return *this;
}

DescriptorBuilder& DescriptorBuilder::signed_item(std::uint8_t type, std::uint8_t tag,
                                                  std::int64_t value) {
  const std::uint8_t size = value >= -128 && value <= 127       ? 1
                            : value >= -32768 && value <= 32767 ? 2
                                                                : 4;
  emit(type, tag, static_cast<std::uint32_t>(value), size);
  return *this;
}

DescriptorBuilder& DescriptorBuilder::range(std::uint8_t tag, std::int64_t min, std::int64_t max) {
  signed_item(1, tag, min);
  if (min < 0) return signed_item(1, static_cast<std::uint8_t>(tag + 1), max);
  return unsigned_item(1, static_cast<std::uint8_t>(tag + 1), static_cast<std::uint32_t>(max));
}

DescriptorBuilder& DescriptorBuilder::padding(ReportKind kind, std::uint32_t bits) {
  report_size(bits).report_count(1);
  const std::uint32_t constant = kMainConstant;
  return kind == ReportKind::kInput    ? input(constant)
         : kind == ReportKind::kOutput ? output(constant)
                                       : feature(constant);
}

std::vector<std::uint8_t> report_profile_descriptor(const ReportProfileLayout& l) {
  DescriptorBuilder b;
  b.usage_page(0xFF00).usage(0x01).collection(kApplication);
  b.logical(0, 255).report_size(8);
  const auto bytes_of = [&](std::uint8_t id, std::size_t length, std::uint16_t u) {
    if (id != 0) b.report_id(id);
    b.usage(u).report_count(static_cast<std::uint32_t>(length));
  };
  bytes_of(l.input.report_id, l.input.length, 0x02);
  b.input(kData);
  bytes_of(l.output.report_id, l.output.length, 0x03);
  b.output(kData);
  std::uint16_t u = 0x04;
  for (const auto* f : {&l.enable_feature, &l.gain_feature, &l.watchdog_feature}) {
    if (!*f) continue;
    bytes_of((*f)->report_id, (*f)->length, u++);
    b.feature(kData);
  }
  b.end_collection();
  return b.bytes();
}

namespace {

using namespace pid;

void block_index(DescriptorBuilder& b) {
  b.usage(kEffectBlockIndex).logical(1, 40).report_size(8).report_count(1).output(kData);
}

void set_effect(DescriptorBuilder& b, std::uint8_t id, int axes) {
  b.usage(kSetEffectReport).collection(kLogical).report_id(id);
  block_index(b);
  b.usage(kEffectType).collection(kLogical).usage(kEtConstantForce);  // the one it renders
  b.logical(1, 1).report_size(8).report_count(1).output(kArray).end_collection();
  b.usage(kDuration).usage(kTriggerRepeatInterval).usage(kSamplePeriod).usage(kStartDelay);
  b.logical(0, 32767).report_size(16).report_count(4).output(kData);
  b.usage(kGain).logical(0, 255).report_size(8).report_count(1).output(kData);
  b.usage(kTriggerButton).logical(1, 8).report_size(8).report_count(1).output(kData);
  if (axes == 1) {
    b.usage(kAxesEnable).collection(kLogical).usage_page(0x01).usage(0x30);
    b.logical(0, 1).report_size(1).report_count(1).output(kData).end_collection();
    b.usage_page(kPage).usage(kDirectionEnable).report_size(1).report_count(1).output(kData);
    b.padding(ReportKind::kOutput, 6);
    b.usage(kDirection).collection(kLogical).usage_page(0x0A).usage(1);
    b.logical(0, 35999).physical(0, 35999).report_size(16).report_count(1).output(kData);
  } else {
    b.usage(kAxesEnable).collection(kLogical).usage_page(0x01).usage(0x30).usage(0x31);
    b.logical(0, 1).report_size(1).report_count(2).output(kData).end_collection();
    b.usage_page(kPage).usage(kDirectionEnable).report_size(1).report_count(1).output(kData);
    b.padding(ReportKind::kOutput, 5);
    b.usage(kDirection).collection(kLogical).usage_page(0x0A).usage(1).usage(2);
    b.logical(0, 36000).physical(0, 36000).report_size(16).report_count(2).output(kData);
  }
  b.end_collection().usage_page(kPage).physical(0, 0).end_collection();
}

void effect_control(DescriptorBuilder& b, const PidReferenceIds& ids) {
  b.usage(kSetConstantForceReport).collection(kLogical).report_id(ids.set_constant);
  block_index(b);
  b.usage(kMagnitude).logical(-10000, 10000).report_size(16).report_count(1).output(kData);
  b.end_collection();
  b.usage(kEffectOperationReport).collection(kLogical).report_id(ids.effect_operation);
  block_index(b);
  b.usage(kEffectOperation).collection(kLogical);
  b.usage(kOpEffectStart).usage(kOpEffectStartSolo).usage(kOpEffectStop);
  b.logical(1, 3).report_size(8).report_count(1).output(kArray).end_collection();
  b.usage(kLoopCount).logical(0, 255).report_size(8).report_count(1).output(kData);
  b.end_collection();
  b.usage(kBlockFreeReport).collection(kLogical).report_id(ids.block_free);
  block_index(b);
  b.end_collection();
}

void device_reports(DescriptorBuilder& b, const PidReferenceOptions& o) {
  const PidReferenceIds& ids = o.ids;
  // The report's collection with its array's collection inside; the SideWinder lineage's: the
  // array's alone.
  if (o.device_control_report) {
    b.usage(kDeviceControlReport).collection(kLogical).report_id(ids.device_control);
    b.usage(kDeviceControl).collection(kLogical);
  } else {
    b.usage(kDeviceControl).collection(kLogical).report_id(ids.device_control);
  }
  b.usage_min(kDcEnableActuators).usage_max(0x9C);
  b.logical(1, 6).report_size(8).report_count(1).output(kArray).end_collection();
  if (o.device_control_report) b.end_collection();
  b.usage(kDeviceGainReport).collection(kLogical).report_id(ids.device_gain);
  b.usage(kDeviceGain).logical(0, 255).report_size(8).report_count(1).output(kData);
  b.end_collection();
  b.usage(kCreateNewEffectReport).collection(kLogical).report_id(ids.create_effect);
  b.usage(kEffectType).collection(kLogical).usage(kEtConstantForce);
  b.logical(1, 1).report_size(8).report_count(1).feature(kArray).end_collection();
  b.end_collection();
  b.usage(kBlockLoadReport).collection(kLogical).report_id(ids.block_load);
  b.usage(kEffectBlockIndex).logical(1, 40).report_size(8).report_count(1).feature(kData);
  b.usage(kBlockLoadStatus).collection(kLogical);
  b.usage(kBlockLoadSuccess).usage(kBlockLoadFull).usage(kBlockLoadError);
  b.logical(1, 3).report_size(8).report_count(1).feature(kArray).end_collection();
  b.usage(kRamPoolAvailable).logical(0, 65535).report_size(16).report_count(1).feature(kData);
  b.end_collection();
  // PID Pool (HID PID 1.0 5.6): the pool's size, the effects it plays at once, and that the
  // device manages its memory itself (hid-pidff refuses a device that does not).
  b.usage(kPoolReport).collection(kLogical).report_id(ids.pool);
  b.usage(kRamPoolSize).logical(0, 65535).report_size(16).report_count(1).feature(kData);
  b.usage(kSimultaneousEffectsMax).logical(0, 255).report_size(8).report_count(1).feature(kData);
  b.usage(kDeviceManagedPool).usage(kSharedParameterBlocks).logical(0, 1).report_size(1);
  b.report_count(2).feature(kData);
  b.padding(ReportKind::kFeature, 6);
  b.end_collection();
}

// Set Envelope (HID PID 1.0 5.3): attack and fade of an effect. hapticd's constant force never
// has one, but a PID host offers constant force only on a device that can take one.
void envelope(DescriptorBuilder& b, std::uint8_t id) {
  b.usage(kSetEnvelopeReport).collection(kLogical).report_id(id);
  block_index(b);
  b.usage(kAttackLevel).usage(kFadeLevel).logical(0, 10000).report_size(16).report_count(2);
  b.output(kData);
  b.usage(kAttackTime).usage(kFadeTime).logical(0, 32767).report_size(16).report_count(2);
  b.output(kData);
  b.end_collection();
}

void state_report(DescriptorBuilder& b, std::uint8_t id) {
  b.usage(kStateReport).collection(kLogical).report_id(id);
  b.usage(kDevicePaused).usage(kActuatorsEnabled).usage(kSafetySwitch);
  b.usage(kActuatorOverrideSwitch).usage(kActuatorPower);
  b.logical(0, 1).report_size(1).report_count(5).input(kData);
  b.padding(ReportKind::kInput, 3);
  b.usage(kEffectPlaying).report_size(1).report_count(1).input(kData);
  b.usage(kEffectBlockIndex).logical(1, 40).report_size(7).report_count(1).input(kData);
  b.end_collection();
}

}  // namespace

std::vector<std::uint8_t> pid_reference_descriptor(const PidReferenceOptions& o) {
  DescriptorBuilder b;
  b.usage_page(0x01).usage(0x04).collection(kApplication);        // Joystick
  b.report_id(o.ids.position).usage(0x01).collection(kPhysical);  // Pointer
  b.usage(0x30);
  if (o.axes == 2) b.usage(0x31);
  b.logical(-32767, 32767)
      .report_size(16)
      .report_count(static_cast<std::uint32_t>(o.axes))
      .input(kData);
  b.end_collection();
  if (o.sequence) {
    b.usage_page(0xFF00).usage(0x20).logical(0, 255).report_size(8).report_count(1).input(kData);
  }
  b.usage_page(kPage);
  if (o.state_report) state_report(b, o.ids.state);
  set_effect(b, o.ids.set_effect, o.axes);
  envelope(b, o.ids.set_envelope);
  effect_control(b, o.ids);
  device_reports(b, o);
  b.end_collection();
  return b.bytes();
}

}  // namespace hapticd::drivers::hid
