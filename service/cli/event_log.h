// Where events (gate verdict, faults, lifecycle) go: stderr, through spdlog; stdout carries
// only the results a script reads (the check table or JSON, the run summary). Under systemd,
// with stderr the journal's stream, each line carries its priority. Not RT-safe.
#pragma once

namespace hapticd::service::cli {

// Sets the default logger up. Returns the prefix of an error line written to stderr directly
// (the journal's error priority "<3>" under systemd, "" otherwise).
const char* set_up_event_log();

}  // namespace hapticd::service::cli
