// What the config and gate fuzz targets assert about one configuration load. Loading may fail
// only with a ConfigError whose every message says where the problem is; any other exception
// escapes to libFuzzer, which reports it as a finding. A load that succeeds goes through the
// gate as `hapticd check` and `run` would, and a passing verdict must rest on a finite,
// checked bound: a safety gate that passes on an overflow or a NaN is worse than none.
#pragma once

#include <initializer_list>
#include <string_view>

#include "config/config.h"
#include "config/config_loader.h"
#include "control/derived_check.h"

namespace hapticd::fuzz {

// Every message of e is non-empty and starts with one of `prefixes` (a source name with its
// ':' such as "fuzz.yaml:", or "--set ") followed by what is wrong.
void check_config_error(const config::ConfigError& e,
                        std::initializer_list<std::string_view> prefixes);

// Runs the gate on cfg with the delay its driver declares, renders the report both ways, and
// checks the verdict: reasons exactly when it fails, and on a pass a finite bound within the
// available damping, a finite sample period, and a control law with finite coefficients.
// A configuration already checked in this process is skipped (see first_time).
void check_gate(const config::Config& cfg);

// load() either returns a Config, which is checked as the daemon checks one after loading
// (service/config_source.cpp: the quantities derived from several keys must be finite) and
// then goes through check_gate, or throws a ConfigError, which goes through
// check_config_error.
template <typename Load>
void check_load_then_gate(Load&& load, std::initializer_list<std::string_view> prefixes) {
  config::Config cfg;
  try {
    cfg = load();
    control::check_derived_quantities(cfg);
  } catch (const config::ConfigError& e) {
    check_config_error(e, prefixes);
    return;
  }
  check_gate(cfg);
}

}  // namespace hapticd::fuzz
