// Compiled with hapticd_control's include paths only: its own headers are there.
#include "control/controller.h"
