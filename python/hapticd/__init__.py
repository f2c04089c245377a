"""Client of hapticd, the real-time haptic servo daemon: its control socket and the shared
state block of the servo loop's samples. Names follow CRTK (measured_js, measured_cp,
measured_cv, setpoint_cf)."""

from .client import Client
from .errors import ClientError, HapticdError, Refused, StateError
from .state import JointState, Sample, State, TickFlag

__all__ = ["Client", "ClientError", "HapticdError", "JointState", "Refused", "Sample", "State",
           "StateError", "TickFlag"]
__version__ = "0.1.0"
