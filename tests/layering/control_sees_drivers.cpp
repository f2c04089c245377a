// Compiled with hapticd_control's include paths only: the Device seam must not be reachable
// from the controller (the test expects this to fail to compile).
#include "drivers/device.h"
