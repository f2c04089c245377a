// `hapticd devices`: what each driver of this build finds attached (HID devices through
// hidapi, ...), each with the configuration keys that select it.
#pragma once

namespace hapticd::service {

// Exit 0; a driver that cannot ask the system says so in its section.
int devices_command();

}  // namespace hapticd::service
