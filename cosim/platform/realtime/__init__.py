"""The platform in real time (docs/guide/realtime.md): what a scene's stream carries and how a
live input drives it (`live`), the motion envelope that input is held in (`envelope`), and the
live view in the browser (`view`). The generic part, the pacing, the datagrams and the sockets, is
cosim.engine.realtime."""

from .envelope import GUARD_KINDS, Envelope, check_reference, within
from .live import LEG_OUTPUTS, check_scene_reference, live_input, real_time_plan, stream_fields, stream_names

__all__ = ["GUARD_KINDS", "Envelope", "check_reference", "within", "LEG_OUTPUTS", "check_scene_reference",
           "live_input", "real_time_plan", "stream_fields", "stream_names"]
