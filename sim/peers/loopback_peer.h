// A loopback peer: the simulated device at the other end of a driver's transport (docs/devices.md).
// It owns a SimAxis, speaks the driver's own bytes on its end of a socketpair (or of a real kernel
// facility: vcan, a USB HID gadget, gpio-sim), and steps the plant on the protocol's own trigger -
// an output report, a CAN SYNC, a PWM write - as the device's firmware would. `hapticd run
// --loopback` and the conformance suite drive a driver against its peer, so the driver's protocol
// code runs exactly as it would with hardware.
#pragma once

#include <string_view>

#include "sim/plant.h"

namespace hapticd::sim {

class JointPlant;

// Faults a peer can be told to produce, for the conformance suite and the kernel tests.
enum class PeerFault {
  kStopAnswering,   // no more samples (a device that hangs, a cable pulled): stale data
  kSkipSequence,    // the next sample skips sequence numbers (reports lost on the way)
  kDeviceFault,     // the device reports a fault (status bit, EMCY, axis error)
  kTransportFault,  // the transport fails (the device vanishes, the bus goes off)
};

std::string_view to_string(PeerFault fault) noexcept;

class LoopbackPeer {
 public:
  virtual ~LoopbackPeer() = default;

  // Not RT-safe; called on the peer's own thread (PeerRunner). Handles every message waiting
  // on its end of the transport and answers as the device would. Never blocks.
  virtual void service() = 0;
  // Its end of the transport, for poll(2); -1 for a peer that lives inside its driver (sim).
  virtual int fd() const noexcept = 0;
  // How often service() must run even when nothing arrived (a device's own timers: heartbeats
  // produced, watchdogs that expire when the master goes silent), in ms; -1: only on input.
  virtual int service_interval_ms() const noexcept { return -1; }

  // Any thread. What the person holding the device feels: the force the plant is given and
  // whether the simulated amplifier is on.
  virtual double applied_force() const noexcept = 0;
  virtual bool output_on() const noexcept = 0;
  // After the run (the peer thread joined): the plant, for the operator's work.
  virtual const Plant& plant() const noexcept = 0;
  // After the run: the mechanism of a device of several joints its drives moved together;
  // null when plant() is the device.
  virtual const JointPlant* joint_plant() const noexcept { return nullptr; }

  // Not RT-safe. For a peer with threads of its own (the raw USB gadget): ends them, so the
  // device is gone and plant() may be read; the others have nothing to stop.
  virtual void stop() noexcept {}

  // Any thread. Produce `fault` from now on (kSkipSequence: once). False when the protocol has
  // no way to express it (e.g. a transport without sequence numbers).
  virtual bool inject(PeerFault fault) noexcept = 0;
};

}  // namespace hapticd::sim
